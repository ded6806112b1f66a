// Every kind of bad input gets a message naming the problem and its 1-based column, never a crash.
#include <gtest/gtest.h>

#include <string>

#include "expr/compile.h"

namespace isomesh {
namespace {

struct ErrorCase {
    std::string source;
    std::string message;
    int column;
};

void expect_error(const ErrorCase& c, const CompileLimits& limits = {}) {
    CompileResult result = compile_expression(c.source, limits);
    ASSERT_FALSE(result.ok()) << c.source;
    EXPECT_EQ(result.error->message, c.message) << c.source;
    EXPECT_EQ(result.error->column, c.column) << c.source;
    EXPECT_TRUE(result.tape.code.empty());
}

TEST(CompileExpression, errors_name_problem_and_column) {
    const ErrorCase cases[] = {
        {"", "empty input", 0},
        {" \t\n ", "empty input", 0},
        {"x+1)", "unexpected ')'", 4},
        {"(x+1", "unclosed '('", 1},
        {"sin(x", "unclosed '('", 4},
        {"2(x+(y)", "unclosed '('", 2},
        {"|x", "unclosed '|'", 1},
        {"x+", "unexpected end of input", 3},
        {"x = ", "unexpected end of input", 5},
        {"= x", "unexpected '='", 1},
        {"()", "unexpected ')'", 2},
        {"x,y", "unexpected ','", 2},
        {"(x=1)", "unexpected '='", 3},
        {"foo(x)", "unknown function 'foo'", 1},
        {"2 + bar(x)", "unknown function 'bar'", 5},
        {"sin x", "expected '(' after 'sin'", 5},
        {"sin", "expected '(' after 'sin'", 4},
        {"sin(x, y)", "sin takes 1 argument, got 2", 1},
        {"sin()", "sin takes 1 argument, got 0", 1},
        {"atan2(x)", "atan2 takes 2 arguments, got 1", 1},
        {"min(x)", "min takes at least 2 arguments, got 1", 1},
        {"log(x, y, z)", "log takes 1 or 2 arguments, got 3", 1},
        {"min(x,)", "unexpected ')'", 7},
        {"x^^2", "unexpected '^'", 3},
        {"x**2", "unexpected '*'", 3},
        {"x=1=2", "more than one '='", 4},
        {"x==1", "more than one '='", 3},
        {"nan", "'nan' is not a finite number", 1},
        {"x + NaN", "'NaN' is not a finite number", 5},
        {"x+inf", "'inf' is not a finite number", 3},
        {"Infinity - x", "'Infinity' is not a finite number", 1},
        {"x+∞", "'∞' is not a finite number", 3},
        {"1e999 + x", "number out of range '1e999'", 1},
        {"x + 1e-999", "number out of range '1e-999'", 5},
        {"1.2.3", "malformed number '1.2.3'", 1},
        {"x + .", "malformed number '.'", 5},
        {"x $ y", "unexpected character '$'", 3},
        {"x [y]", "unexpected character '['", 3},
        {"x!", "unexpected character '!'", 2},
        {"x\x01", "unexpected character U+0001", 2},
        {"x+\xff", "invalid UTF-8", 3},
        {"x+\xc3", "invalid UTF-8", 3},          // truncated sequence
        {"x+\xc0\xaf", "invalid UTF-8", 3},      // overlong '/'
        {"x+\xed\xa0\x80", "invalid UTF-8", 3},  // surrogate
        {"π·x + )", "unexpected ')'", 7},        // columns count characters
        {"x⁻", "superscript minus without digits", 2},
        {"x¹²³⁴⁵", "superscript exponent too large '¹²³⁴⁵'", 2},
        {"sin⁻¹(x)", "ambiguous '⁻¹' after 'sin': write 1/sin(...) or the inverse function", 4},
    };
    for (const ErrorCase& c : cases) expect_error(c);
}

TEST(CompileExpression, inequalities_are_refused_as_regions) {
    const std::pair<std::string, std::string> cases[] = {
        {"x<1", "'<'"},   {"x <= 1", "'<='"}, {"x>1", "'>'"}, {"x>=1", "'>='"},
        {"x!=1", "'!='"}, {"x≤1", "'≤'"},     {"x≥1", "'≥'"}, {"x≠1", "'≠'"},
    };
    for (const auto& [source, symbol] : cases) {
        int column = source[1] == ' ' ? 3 : 2;
        expect_error({source,
                      "inequalities describe regions, not surfaces: use '=' instead of " + symbol,
                      column});
    }
}

TEST(CompileError, to_string_names_column_or_line) {
    EXPECT_EQ(compile_expression("x+1)").error->to_string(), "unexpected ')' at column 4");
    EXPECT_EQ(compile_expression("x +\n  )").error->to_string(),
              "unexpected ')' at line 2, column 3");
    EXPECT_EQ(compile_expression("").error->to_string(), "empty input");
}

TEST(CompileExpression, error_messages_stay_short_and_printable) {
    std::string name = "q" + std::string(5000, 'w') + "(x)";
    CompileResult result = compile_expression(name);
    ASSERT_FALSE(result.ok());
    EXPECT_LT(result.error->message.size(), 80u);
    EXPECT_EQ(result.error->message.rfind("unknown function 'qwww", 0), 0u);
}

TEST(CompileLimits, source_length_is_limited) {
    std::string megabyte_of_parens(1 << 20, '(');
    CompileResult result = compile_expression(megabyte_of_parens);
    ASSERT_FALSE(result.ok());
    EXPECT_EQ(result.error->message, "input too long: 1048576 bytes, the limit is 65536");

    CompileLimits small;
    small.max_source_bytes = 4;
    EXPECT_TRUE(compile_expression("x+y", small).ok());
    EXPECT_FALSE(compile_expression("x + y", small).ok());
}

TEST(CompileLimits, nesting_depth_is_limited_without_stack_overflow) {
    CompileLimits huge_source;
    huge_source.max_source_bytes = 2 << 20;
    expect_error({std::string(1 << 20, '('), "nesting deeper than 256 levels", 257}, huge_source);
    expect_error({std::string(1 << 20, '|'), "nesting deeper than 256 levels", 257}, huge_source);
    expect_error({std::string(300, '-') + "x", "nesting deeper than 256 levels", 257});
    std::string power_tower = "x";
    for (int i = 0; i < 300; ++i) power_tower += "^x";
    expect_error({power_tower, "nesting deeper than 256 levels", 2 * 257}, huge_source);
    std::string calls;
    for (int i = 0; i < 300; ++i) calls += "sin(";
    expect_error({calls, "nesting deeper than 256 levels", 4 * 257}, huge_source);
}

TEST(CompileLimits, nesting_at_the_limit_compiles) {
    std::string deepest = std::string(256, '(') + "x" + std::string(256, ')');
    EXPECT_TRUE(compile_expression(deepest).ok());
    CompileLimits shallow;
    shallow.max_depth = 2;
    EXPECT_TRUE(compile_expression("((x))", shallow).ok());
    expect_error({"(((x)))", "nesting deeper than 2 levels", 3}, shallow);
}

TEST(CompileLimits, instruction_count_is_limited) {
    CompileLimits limits;
    limits.max_instructions = 11;
    // x, 2 (the exponent, emitted before x^2 becomes square(x)), x², y, y², +, z, z², +, 1, -
    EXPECT_TRUE(compile_expression("x^2 + y^2 + z^2 = 1", limits).ok());
    expect_error({"x^2 + y^2 + z^2 + 1 = 3", "the expression needs more than 11 instructions", 0},
                 limits);
    CompileLimits large_source;
    large_source.max_source_bytes = 1 << 20;
    std::string long_product(200000, 'x');  // x*x*...: one new instruction per letter
    expect_error({long_product, "the expression needs more than 100000 instructions", 0},
                 large_source);
    expect_error({long_product, "input too long: 200000 bytes, the limit is 65536", 0});
}

TEST(CompileLimits, parameter_count_is_limited) {
    CompileLimits limits;
    limits.max_parameters = 2;
    EXPECT_TRUE(compile_expression("a x + b y + a", limits).ok());
    expect_error({"a x + b y + c", "more than 2 parameters", 13}, limits);
}

}  // namespace
}  // namespace isomesh
