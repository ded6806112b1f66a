// The language features of compile_expression: each construct compiles to the same tape as its
// explicit spelling, and to the right values at sample points.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>

#include "expr/compile.h"
#include "tape_interpreter.h"

namespace isomesh {
namespace {

using testing::count_ops;
using testing::interpret;

Tape compiled(std::string_view source) {
    CompileResult result = compile_expression(source);
    EXPECT_TRUE(result.ok()) << source << ": " << (result.error ? result.error->to_string() : "");
    return result.tape;
}

void expect_same_tape(std::string_view typed, std::string_view explicit_form) {
    EXPECT_EQ(compiled(typed).dump(), compiled(explicit_form).dump())
        << typed << " should read as " << explicit_form;
}

struct Point {
    double x, y, z;
};
constexpr Point kPoints[] = {
    {0.3, -0.7, 1.1}, {-1.3, 0.4, -0.2}, {2.1, 1.7, -0.9}, {0.5, 0.5, 0.5}};

using Reference = std::function<double(double, double, double)>;

void expect_values(std::string_view source, const Reference& reference) {
    Tape tape = compiled(source);
    for (const Point& p : kPoints) {
        double expected = reference(p.x, p.y, p.z);
        double actual = interpret(tape, p.x, p.y, p.z);
        if (std::isnan(expected)) {
            EXPECT_TRUE(std::isnan(actual)) << source << " at " << p.x << "," << p.y << "," << p.z;
        } else {
            EXPECT_NEAR(actual, expected, 1e-12 * (1 + std::abs(expected)))
                << source << " at " << p.x << "," << p.y << "," << p.z;
        }
    }
}

TEST(CompileExpression, equation_is_lhs_minus_rhs) {
    expect_same_tape("x^2 + y^2 = z", "x^2 + y^2 - (z)");
    expect_same_tape("3 = x", "3 - x");
    expect_values("x^2+y^2+z^2=1",
                  [](double x, double y, double z) { return x * x + y * y + z * z - 1; });
}

TEST(CompileExpression, numbers_read_every_spelling) {
    expect_values("2 + .5 + 1e-3 + 2.5E2 + 3. + 1e+1",
                  [](double, double, double) { return 2 + .5 + 1e-3 + 2.5e2 + 3. + 1e+1; });
    expect_same_tape("2e", "2*e");  // no exponent digits: 2 times e
    expect_same_tape("2e-x", "2*e - x");
}

TEST(CompileExpression, constants_are_pi_and_e) {
    expect_same_tape("pi", "π");
    expect_values("pi x + e",
                  [](double x, double, double) { return std::numbers::pi * x + std::numbers::e; });
}

TEST(CompileExpression, power_is_right_associative_below_prefix_minus) {
    expect_same_tape("x^y^z", "x^(y^z)");
    expect_same_tape("-x^2", "-(x^2)");
    expect_same_tape("x^-2", "x^(-2)");
    expect_same_tape("2^-x y", "(2^(-x))*y");
    expect_same_tape("-2x", "(-2)*x");
    expect_values("2^3^2 + x", [](double x, double, double) { return 512 + x; });
    expect_values("-x^2", [](double x, double, double) { return -(x * x); });
}

TEST(CompileExpression, implicit_multiplication_reads_as_geogebra) {
    expect_same_tape("2x", "2*x");
    expect_same_tape("2cos(2x)", "2*cos(2*x)");
    expect_same_tape("xy", "x*y");
    expect_same_tape("xyz", "x*y*z");
    expect_same_tape("xy^2", "x*y^2");
    expect_same_tape("2xy²z", "2*x*y^2*z");
    expect_same_tape("xx", "x^2");
    // A letter other than x, y, z makes the whole word one parameter name.
    EXPECT_EQ(compiled("xa + ya").params, (std::vector<std::string>{"xa", "ya"}));
    expect_same_tape("x y z", "x*y*z");
    expect_same_tape("(x+1)(x-1)", "(x+1)*(x-1)");
    expect_same_tape("2(x+1)", "2*(x+1)");
    expect_same_tape("3sin(x)^2", "3*(sin(x)^2)");
    expect_same_tape("a(x+1)", "a*(x+1)");
    expect_same_tape("x(x+1)", "x*(x+1)");
    expect_same_tape("sin(x)cos(y)", "sin(x)*cos(y)");
    expect_same_tape("1/2x", "(1/2)*x");
    expect_same_tape("2|x|", "2*abs(x)");
    expect_same_tape("x²y", "x^2*y");
}

TEST(CompileExpression, unicode_operators_and_superscripts) {
    expect_same_tape("x²+y³", "x^2+y^3");
    expect_same_tape("x⁻¹ + y¹⁰", "x^(-1) + y^10");
    expect_same_tape("x·y×z⋅x", "x*y*z*x");
    expect_same_tape("x÷y", "x/y");
    expect_same_tape("x−y", "x-y");  // U+2212
    expect_same_tape("x\u00A0+\ty\n+ z", "x+y+z");
    expect_same_tape("-x²", "-(x^2)");
    expect_same_tape("x^y²", "x^(y^2)");
}

TEST(CompileExpression, bars_are_absolute_values) {
    expect_same_tape("|x|", "abs(x)");
    expect_same_tape("||x|-1|", "abs(abs(x)-1)");
    expect_same_tape("|x||y|", "abs(x)*abs(y)");
    expect_same_tape("|x + |y||", "abs(x + abs(y))");
    expect_same_tape("|(x|y|)|", "abs(x*abs(y))");
    expect_values("|x|+|y-1|",
                  [](double x, double y, double) { return std::abs(x) + std::abs(y - 1); });
}

TEST(CompileExpression, functions_match_std_math) {
    const std::pair<const char*, Reference> cases[] = {
        {"sin(x)", [](double x, double, double) { return std::sin(x); }},
        {"cos(x)", [](double x, double, double) { return std::cos(x); }},
        {"tan(x)", [](double x, double, double) { return std::tan(x); }},
        {"asin(x/3)", [](double x, double, double) { return std::asin(x / 3); }},
        {"arcsin(x/3)", [](double x, double, double) { return std::asin(x / 3); }},
        {"acos(x/3)", [](double x, double, double) { return std::acos(x / 3); }},
        {"arccos(x/3)", [](double x, double, double) { return std::acos(x / 3); }},
        {"atan(x)", [](double x, double, double) { return std::atan(x); }},
        {"arctan(x)", [](double x, double, double) { return std::atan(x); }},
        {"atan2(y, x)", [](double x, double y, double) { return std::atan2(y, x); }},
        {"sinh(x)", [](double x, double, double) { return std::sinh(x); }},
        {"cosh(x)", [](double x, double, double) { return std::cosh(x); }},
        {"tanh(x)", [](double x, double, double) { return std::tanh(x); }},
        {"exp(x)", [](double x, double, double) { return std::exp(x); }},
        {"ln(x)", [](double x, double, double) { return std::log(x); }},
        {"log(x)", [](double x, double, double) { return std::log(x); }},
        {"log(2, y)", [](double, double y, double) { return std::log(y) / std::log(2.0); }},
        {"lg(x)", [](double x, double, double) { return std::log10(x); }},
        {"log10(x)", [](double x, double, double) { return std::log10(x); }},
        {"ld(x)", [](double x, double, double) { return std::log2(x); }},
        {"log2(x)", [](double x, double, double) { return std::log2(x); }},
        {"sqrt(x)", [](double x, double, double) { return std::sqrt(x); }},
        {"cbrt(x)", [](double x, double, double) { return std::cbrt(x); }},
        {"abs(x)", [](double x, double, double) { return std::abs(x); }},
        {"sgn(x)", [](double x, double, double) { return x > 0 ? 1.0 : -1.0; }},
        {"sign(y)", [](double, double y, double) { return y > 0 ? 1.0 : -1.0; }},
        {"floor(x)", [](double x, double, double) { return std::floor(x); }},
        {"ceil(x)", [](double x, double, double) { return std::ceil(x); }},
        {"round(2x)", [](double x, double, double) { return std::round(2 * x); }},
        {"min(x, y)", [](double x, double y, double) { return std::min(x, y); }},
        {"min(x, y, z)", [](double x, double y, double z) { return std::min({x, y, z}); }},
        {"max(x, y, z, 1)", [](double x, double y, double z) { return std::max({x, y, z, 1.0}); }},
        {"sin²(x)", [](double x, double, double) { return std::sin(x) * std::sin(x); }},
    };
    for (const auto& [source, reference] : cases) expect_values(source, reference);
}

// sqrt of a sum of squares (distances) compiles to hypot, one per extra term, with the values of
// the spelled-out root within rounding.
TEST(CompileExpression, square_roots_of_sums_of_squares_fuse_to_hypot) {
    const Tape distance = compiled("sqrt((x-1)^2 + y^2 + (z+0.5)*(z+0.5))");
    EXPECT_EQ(count_ops(distance, Op::Hypot), 2);
    EXPECT_EQ(count_ops(distance, Op::Sqrt) + count_ops(distance, Op::Square), 0);
    EXPECT_EQ(count_ops(compiled("sqrt(x^2 + y^2)"), Op::Hypot), 1);
    EXPECT_EQ(count_ops(compiled("sqrt(x^2 + y)"), Op::Hypot), 0);
    EXPECT_EQ(count_ops(compiled("sqrt(x^2 - y^2)"), Op::Hypot), 0);
    expect_values("sqrt((x-1)^2 + y^2 + (z+0.5)*(z+0.5))", [](double x, double y, double z) {
        return std::sqrt((x - 1) * (x - 1) + y * y + (z + 0.5) * (z + 0.5));
    });
}

// ln of a sum of exponentials (smooth CSG blends) compiles to logsumexp, one per extra term, with
// positive constants as exponentials of their logarithm: the same values, and finite where an
// exponential overflows.
TEST(CompileExpression, log_of_exponential_sums_fuses_to_logsumexp) {
    EXPECT_EQ(count_ops(compiled("ln(exp(x) + exp(y))"), Op::LogSumExp), 1);
    const Tape blend = compiled("-ln(exp(-8x) + exp(-8y) + exp(-8z))/8");
    EXPECT_EQ(count_ops(blend, Op::LogSumExp), 2);
    EXPECT_EQ(count_ops(blend, Op::Exp) + count_ops(blend, Op::Ln), 0);
    EXPECT_EQ(count_ops(compiled("ln(1 + e^x)"), Op::LogSumExp), 1);
    EXPECT_EQ(count_ops(compiled("ln(exp(x) + y)"), Op::LogSumExp), 0);
    EXPECT_EQ(count_ops(compiled("ln(exp(x) - exp(y))"), Op::LogSumExp), 0);
    EXPECT_EQ(count_ops(compiled("ln(exp(x))"), Op::LogSumExp), 0);
    expect_values("-ln(exp(-8x) + exp(-8y) + exp(-8z))/8", [](double x, double y, double z) {
        return -std::log(std::exp(-8 * x) + std::exp(-8 * y) + std::exp(-8 * z)) / 8;
    });
    expect_values("ln(2 + exp(3x))",
                  [](double x, double, double) { return std::log(2 + std::exp(3 * x)); });
    EXPECT_EQ(interpret(compiled("ln(exp(1000x) + exp(y))"), 1.0, 0.0, 0.0), 1000.0);
}

TEST(CompileExpression, e_power_is_exp) {
    Tape tape = compiled("e^(x y)");
    EXPECT_EQ(count_ops(tape, Op::Exp), 1);
    EXPECT_EQ(count_ops(tape, Op::Pow), 0);
    expect_same_tape("e^-x^2", "exp(-(x^2))");
}

TEST(CompileExpression, whole_exponents_are_powint_or_square) {
    Tape tape = compiled("x^2 + y^3 + z^-4 + x^2.5");
    EXPECT_EQ(count_ops(tape, Op::Square), 1);
    EXPECT_EQ(count_ops(tape, Op::PowInt), 2);
    EXPECT_EQ(count_ops(tape, Op::Pow), 1);
}

TEST(CompileExpression, odd_root_exponents_are_real_for_negative_bases) {
    expect_same_tape("x^(1/3)", "cbrt(x)");
    expect_same_tape("x^(2/3)", "cbrt(x)^2");
    expect_values("x^(2/3) + y^(2/3) + z^(2/3)", [](double x, double y, double z) {
        return std::pow(std::cbrt(x), 2) + std::pow(std::cbrt(y), 2) + std::pow(std::cbrt(z), 2);
    });
    expect_values("x^(1/5)", [](double x, double, double) {
        return (x < 0 ? -1 : 1) * std::pow(std::abs(x), 0.2);
    });
    expect_values("x^0.5", [](double x, double, double) { return std::pow(x, 0.5); });
    expect_values("(-8)^(1/3) + x", [](double x, double, double) { return -2 + x; });
}

TEST(CompileExpression, repeated_subexpressions_are_computed_once) {
    Tape tape = compiled("x^2+x^2+x^2");
    EXPECT_EQ(count_ops(tape, Op::Square), 1);
    Tape shared = compiled("sin(x y) + cos(sin(x y)) = sin(y x)");  // x y and y x commute
    EXPECT_EQ(count_ops(shared, Op::Sin), 1);
    EXPECT_EQ(count_ops(shared, Op::Mul), 1);
}

TEST(CompileExpression, constants_are_folded) {
    Tape tape = compiled("2*3+4 = x");  // 10 - x
    ASSERT_EQ(tape.size(), 3u);
    EXPECT_EQ(count_ops(tape, Op::Const), 1);
    EXPECT_EQ(compiled("sin(0) + x").size(), 1u);  // sin(0) = 0 and x + 0 = x
    EXPECT_EQ(compiled("2^10 + sqrt(16) + ln(e) + pi^2").size(), 1u);
}

TEST(CompileExpression, other_names_are_parameters) {
    Tape tape = compiled("a x + b1 y + α z + r_2 = a");
    EXPECT_EQ(tape.params, (std::vector<std::string>{"a", "b1", "α", "r_2"}));
    std::vector<double> values = {2, 3, 5, 7};
    EXPECT_DOUBLE_EQ(interpret(tape, 1, 1, 1, values), 2 + 3 + 5 + 7 - 2);
    expect_same_tape("ab x", "ab*x");       // a multi-letter parameter, not a*b
    EXPECT_EQ(compiled("2*a").size(), 3u);  // parameters are never folded
}

TEST(CompileExpression, multiline_source_compiles) {
    expect_same_tape("x^2 +\ny^2\r\n= 1", "x^2+y^2-1");
}

}  // namespace
}  // namespace isomesh
