#include "test_support.h"

#include <algorithm>
#include <bit>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include <gtest/gtest.h>

#include "expr/compile.h"
#include "expr/vm_reader.h"

namespace isomesh::testing {

namespace {
constexpr double kPi = std::numbers::pi;
}

std::vector<TestFunction> test_functions() {
    std::vector<TestFunction> f;
    // Written as generic lambdas: the using-declarations pick std:: math for doubles, while ADL
    // finds the Sym overloads of test_support.h for tapes.
#define FUNCTION(name, scale, special, ...)                                                \
    f.push_back(make_function(name, scale, special, [](auto x, auto y, auto z) {           \
        using std::sqrt, std::cbrt, std::abs, std::floor, std::ceil, std::round, std::exp; \
        using std::log, std::log10, std::log2, std::sin, std::cos, std::tan, std::asin;    \
        using std::acos, std::atan, std::sinh, std::cosh, std::tanh, std::pow, std::atan2; \
        (void)x, (void)y, (void)z;                                                         \
        return __VA_ARGS__;                                                                \
    }))
    using P = std::vector<glm::dvec3>;
    FUNCTION("sphere", 2.0, P({}), x * x + y * y + z * z - 1.0);
    FUNCTION("thesis", 15.0, P({{0, 0, 0}}),
             sqrt(x * x + y * y + z * z) + 2 * cos(2 * x) + 2 * cos(2 * y) + 2 * cos(2 * z) - 20);
    FUNCTION("tanglecube", 3.0, P({}),
             pow(x, 4) - 5 * x * x + pow(y, 4) - 5 * y * y + pow(z, 4) - 5 * z * z + 10);
    FUNCTION("reciprocal", 2.0, P({{0, 0, 0}}), 1.0 / x + y * z);
    FUNCTION("tangent", 4.0, P({{kPi / 2, 0, 0}, {-kPi / 2, 1, 0}}), tan(x) - y);
    FUNCTION("logarithms", 3.0, P({{0, 0, 0}, {1, 1, 0}}),
             log(x) + log10(y * y) - log2(abs(z) + 1));
    FUNCTION("roots", 3.0, P({{0, 0, 0}}), sqrt(x) - cbrt(y) + sqrt(x * x + z * z));
    FUNCTION("inverse_trig", 1.5, P({{1, -1, 0}, {-1, 1, 0}}), asin(x) + acos(y) + atan(3 * z));
    FUNCTION("angle", 2.0, P({{0, 0, 0}, {-1, 0, 0}}), atan2(y, x) - z);
    FUNCTION("power", 3.0, P({{0, 0, 0}, {-1, 2, 0}, {0, -1, 0}, {1, 0, 0}}), pow(x, y) + z);
    FUNCTION("whole_powers", 2.0, P({{0, 0, 0}}),
             pow(x, 3) - pow(y, -2) + pow(z, 5) + pow(x * x, 0.5) - pow(z, -3));
    FUNCTION("steps", 3.0, P({{1, 1, 0.5}, {0, 0, 0}, {-0.5, 2, -0.5}}),
             floor(x) + ceil(y) + round(z) + sgn(x * y));
    FUNCTION("hyperbolic", 3.0, P({}), exp(x) - sinh(y) + cosh(z) * tanh(x + y));
    FUNCTION("trigonometry", 10.0, P({}), sin(x * y) + cos(z) * sin(3 * x) - 0.5);
    FUNCTION("csg", 1.5, P({{0, 0, 0}}),
             minimum(maximum(sqrt((x - 0.3) * (x - 0.3) + y * y + z * z) - 0.5, -(z - 0.1)),
                     abs(x + 0.5) + abs(y) + abs(z) - 0.6));
    FUNCTION("rational", 2.0, P({}), (x * y - z) / (x * x + y * y + 0.5) + x * y * z);
    FUNCTION("undefined_min", 2.0, P({{0, 0, 0}}), minimum(sqrt(x), y) + maximum(log(z), x));
    // Smooth CSG as CAD tools write it (bear.vm): a smooth union of three shapes,
    // -ln(sum exp(-k d_i)) / k, which the tape holds as logsumexp; the third term is beyond the
    // cutoff on most boxes. Plus a softplus, ln(1 + exp(3x)) (a constant term).
    FUNCTION("smooth_blend", 2.0, P({}),
             -log(exp(-6 * (sqrt(x * x + y * y + z * z) - 1)) +
                  exp(-6 * (abs(x) + abs(y) + abs(z) - 1.2)) + exp(30 * (0.5 - z))) /
                     6 +
                 0.1 * log(1 + exp(3 * x)));
#undef FUNCTION

    // A parameter: a*x^2 + b*y - z with a = 1.5, b = -2.
    TapeBuilder builder;
    std::uint32_t a = builder.param("a"), b = builder.param("b");
    std::uint32_t x = builder.var(0), y = builder.var(1), z = builder.var(2);
    std::uint32_t ax2 = builder.binary(Op::Mul, a, builder.unary(Op::Square, x));
    std::uint32_t out =
        builder.binary(Op::Sub, builder.binary(Op::Add, ax2, builder.binary(Op::Mul, b, y)), z);
    auto tape = std::make_shared<const Tape>(builder.finish(out));
    auto reference = [](const glm::dvec3& p) { return 1.5 * p.x * p.x + -2.0 * p.y - p.z; };
    f.push_back({"parameters", tape, {1.5, -2.0}, reference, 2.0, {}});
    return f;
}

std::shared_ptr<const Tape> compile_tape(const char* source) {
    CompileResult result = compile_expression(source);
    EXPECT_TRUE(result.ok()) << source << ": " << (result.ok() ? "" : result.error->to_string());
    return std::make_shared<const Tape>(std::move(result.tape));
}

std::shared_ptr<const Tape> load_vm_tape(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("cannot open " + path);
    std::stringstream text;
    text << in.rdbuf();
    CompileResult result = read_vm(text.str());
    if (!result.ok()) throw std::runtime_error(path + ": " + result.error->to_string());
    return std::make_shared<const Tape>(std::move(result.tape));
}

namespace {

double log_uniform(Rng& rng, double lo, double hi) {
    std::uniform_real_distribution<double> u(std::log(lo), std::log(hi));
    return std::exp(u(rng));
}

}  // namespace

Box random_box(Rng& rng, double scale, const std::vector<glm::dvec3>& special) {
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    int kind = static_cast<int>(rng() % 5);
    if (kind == 1 && special.empty()) kind = 0;
    glm::dvec3 center(unit(rng), unit(rng), unit(rng));
    center *= scale;
    glm::dvec3 half;
    for (int axis = 0; axis < 3; ++axis) {
        switch (kind) {
            case 1:  // straddling (or touching) a special point
                center[axis] = special[rng() % special.size()][axis];
                if (rng() % 2) center[axis] += scale * 1e-3 * unit(rng);
                half[axis] = scale * log_uniform(rng, 1e-9, 1.0);
                break;
            case 2:
                half[axis] = scale * log_uniform(rng, 1e-12, 1e-6);
                break;  // tiny
            case 3:
                half[axis] = scale * log_uniform(rng, 1.0, 1e3);
                break;  // huge
            case 4:
                half[axis] = rng() % 2 ? 0.0 : scale * log_uniform(rng, 1e-6, 1.0);
                break;
            default:
                half[axis] = scale * log_uniform(rng, 1e-6, 1.0);
                break;
        }
    }
    if (kind == 1 && rng() % 2) {  // one face exactly on the special point
        int axis = static_cast<int>(rng() % 3);
        return {center - half * glm::dvec3(axis == 0 ? 0 : 1, axis == 1 ? 0 : 1, axis == 2 ? 0 : 1),
                center + half};
    }
    return {center - half, center + half};
}

std::vector<glm::dvec3> points_in(Rng& rng, const Box& box, const std::vector<glm::dvec3>& special,
                                  int random_count) {
    std::vector<glm::dvec3> points;
    for (int corner = 0; corner < 8; ++corner) {
        points.emplace_back(corner & 1 ? box.hi.x : box.lo.x, corner & 2 ? box.hi.y : box.lo.y,
                            corner & 4 ? box.hi.z : box.lo.z);
    }
    points.push_back(box.center());
    for (const glm::dvec3& s : special) points.push_back(glm::clamp(s, box.lo, box.hi));
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int i = 0; i < random_count; ++i) {
        glm::dvec3 t(unit(rng), unit(rng), unit(rng));
        points.push_back(glm::clamp(box.lo + t * box.size(), box.lo, box.hi));
    }
    return points;
}

bool same_value(double a, double b) {
    return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b) ||
           (std::isnan(a) && std::isnan(b));
}

}  // namespace isomesh::testing
