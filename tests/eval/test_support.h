// Helpers for the evaluator tests: functions written once as generic lambdas and instantiated on
// double (the std:: reference) and on Sym (which writes the tape), random boxes and points.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <glm/common.hpp>

#include "eval/evaluator.h"
#include "tape/tape.h"

namespace isomesh::testing {

/// A tape slot under construction; arithmetic on it emits instructions.
struct Sym {
    TapeBuilder* builder;
    std::uint32_t slot;
};

inline Sym constant_like(const Sym& s, double c) {
    return {s.builder, s.builder->constant(c)};
}
inline Sym apply(Op op, Sym a) {
    return {a.builder, a.builder->unary(op, a.slot)};
}
inline Sym apply(Op op, Sym a, Sym b) {
    return {a.builder, a.builder->binary(op, a.slot, b.slot)};
}

inline Sym operator-(Sym a) {
    return apply(Op::Neg, a);
}
#define ISOMESH_SYM_BINARY(symbol, op)            \
    inline Sym operator symbol(Sym a, Sym b) {    \
        return apply(op, a, b);                   \
    }                                             \
    inline Sym operator symbol(Sym a, double b) { \
        return apply(op, a, constant_like(a, b)); \
    }                                             \
    inline Sym operator symbol(double a, Sym b) { \
        return apply(op, constant_like(b, a), b); \
    }
ISOMESH_SYM_BINARY(+, Op::Add)
ISOMESH_SYM_BINARY(-, Op::Sub)
ISOMESH_SYM_BINARY(*, Op::Mul)
ISOMESH_SYM_BINARY(/, Op::Div)
#undef ISOMESH_SYM_BINARY

#define ISOMESH_SYM_UNARY(name, op) \
    inline Sym name(Sym a) {        \
        return apply(op, a);        \
    }
ISOMESH_SYM_UNARY(sqrt, Op::Sqrt)
ISOMESH_SYM_UNARY(cbrt, Op::Cbrt)
ISOMESH_SYM_UNARY(abs, Op::Abs)
ISOMESH_SYM_UNARY(sgn, Op::Sgn)
ISOMESH_SYM_UNARY(floor, Op::Floor)
ISOMESH_SYM_UNARY(ceil, Op::Ceil)
ISOMESH_SYM_UNARY(round, Op::Round)
ISOMESH_SYM_UNARY(exp, Op::Exp)
ISOMESH_SYM_UNARY(log, Op::Ln)
ISOMESH_SYM_UNARY(log10, Op::Log10)
ISOMESH_SYM_UNARY(log2, Op::Log2)
ISOMESH_SYM_UNARY(sin, Op::Sin)
ISOMESH_SYM_UNARY(cos, Op::Cos)
ISOMESH_SYM_UNARY(tan, Op::Tan)
ISOMESH_SYM_UNARY(asin, Op::Asin)
ISOMESH_SYM_UNARY(acos, Op::Acos)
ISOMESH_SYM_UNARY(atan, Op::Atan)
ISOMESH_SYM_UNARY(sinh, Op::Sinh)
ISOMESH_SYM_UNARY(cosh, Op::Cosh)
ISOMESH_SYM_UNARY(tanh, Op::Tanh)
#undef ISOMESH_SYM_UNARY

inline Sym pow(Sym a, Sym b) {
    return apply(Op::Pow, a, b);
}
inline Sym pow(Sym a, double b) {
    return apply(Op::Pow, a, constant_like(a, b));
}
inline Sym pow(Sym a, int n) {
    return {a.builder, a.builder->pow_int(a.slot, n)};
}
inline Sym atan2(Sym a, Sym b) {
    return apply(Op::Atan2, a, b);
}
inline Sym minimum(Sym a, Sym b) {
    return apply(Op::Min, a, b);
}
inline Sym maximum(Sym a, Sym b) {
    return apply(Op::Max, a, b);
}

// The std:: reference for the names std:: lacks or spells differently.
inline double sgn(double v) {
    return v > 0 ? 1.0 : v < 0 ? -1.0 : v == 0 ? 0.0 : v;
}
inline double minimum(double a, double b) {
    return std::isnan(a) || std::isnan(b) ? NAN : std::min(a, b);
}
inline double maximum(double a, double b) {
    return std::isnan(a) || std::isnan(b) ? NAN : std::max(a, b);
}

/// The tape of a function written as a generic lambda f(x, y, z).
template <class F>
std::shared_ptr<const Tape> tape_of(const F& f) {
    TapeBuilder builder;
    Sym x{&builder, builder.var(0)}, y{&builder, builder.var(1)}, z{&builder, builder.var(2)};
    return std::make_shared<const Tape>(builder.finish(f(x, y, z).slot));
}

/// A test function: its tape, the same function in std:: math (null when there is none), and
/// where to sample it.
struct TestFunction {
    std::string name;
    std::shared_ptr<const Tape> tape;
    std::vector<double> params;
    std::function<double(const glm::dvec3&)> reference;
    double scale = 1.0;  // random points lie in [-scale, scale]^3
    /// Points near which the function jumps, has a pole or stops being defined: random boxes are
    /// also centred there, and the points of the boxes nearest to them are sampled.
    std::vector<glm::dvec3> special;
};

template <class F>
TestFunction make_function(std::string name, double scale, std::vector<glm::dvec3> special,
                           const F& f) {
    auto reference = [f](const glm::dvec3& p) { return f(p.x, p.y, p.z); };
    return {std::move(name), tape_of(f), {}, reference, scale, std::move(special)};
}

/// The functions every tape backend is tested on.
std::vector<TestFunction> test_functions();

/// The tape of an expression of the language (expr/compile.h); a test failure if it does not
/// compile.
std::shared_ptr<const Tape> compile_tape(const char* source);

/// A tape read from a Fidget .vm file (format in testdata/README.md), for prospero and bear.
std::shared_ptr<const Tape> load_vm_tape(const std::string& path);

using Rng = std::mt19937_64;

/// A random box: ordinary, centred near a special point, tiny, huge or flat (some lo == hi).
Box random_box(Rng& rng, double scale, const std::vector<glm::dvec3>& special);

/// Points of `box`: its corners and centre, the points nearest to each special point, and
/// `random_count` uniform random ones.
std::vector<glm::dvec3> points_in(Rng& rng, const Box& box, const std::vector<glm::dvec3>& special,
                                  int random_count);

/// True when a and b are the same double bit for bit, or both NaN.
bool same_value(double a, double b);

}  // namespace isomesh::testing
