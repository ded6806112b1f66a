// Forward-mode automatic differentiation over a tape (Wengert 1964; Griewank & Walther, "Evaluating
// Derivatives", 2008, chapter 3), written once for two number types:
//   - double: dual numbers, f and grad f at a point (Evaluator::value_gradient);
//   - IntervalValue: interval forward mode, enclosures of f and grad f over a box
//     (Evaluator::interval_gradient).
// Because both run the very same derivative formulas, operation by operation, and each interval
// operation encloses its point counterpart, the interval gradient encloses the computed point
// gradient at every point of the box (where that gradient is a number).
#pragma once

#include <cassert>
#include <cmath>
#include <numbers>
#include <span>
#include <vector>

#include "eval/interval_math.h"
#include "eval/interval_ranges.h"
#include "eval/tape_arithmetic.h"
#include "eval/tape_ops.h"
#include "eval/tape_simplify.h"

namespace isomesh::forward_mode {

using arithmetic::binary;
using arithmetic::constant;
using arithmetic::unary;

/// partial * d, exactly 0 when the tangent d is 0: a zero tangent contributes nothing, even where
/// the partial is infinite or NaN (x^c with a negative base has ln(x) = NaN in d/dc, but c is
/// constant).
inline double term(double partial, double d) {
    return d == 0.0 ? 0.0 : partial * d;
}
inline IntervalValue term(const IntervalValue& partial, const IntervalValue& d) {
    if (d.value.lo == 0.0 && d.value.hi == 0.0) return constant<IntervalValue>(0.0);
    IntervalValue t = interval_binary(Op::Mul, partial, d);
    if (d.value.contains(0.0)) t.value = hull(t.value, {0.0, 0.0});
    return t;
}

/// d op(a) / da, from the operand a and the result r = op(a).
template <class T>
T unary_partial(Op op, const T& a, const T& r, double imm) {
    auto c = [](double v) { return constant<T>(v); };
    auto mul = [](const T& x, const T& y) { return binary(Op::Mul, x, y); };
    auto div = [](const T& x, const T& y) { return binary(Op::Div, x, y); };
    auto square = [](const T& x) { return unary(Op::Square, x); };
    switch (op) {
        case Op::Neg:
            return c(-1.0);
        case Op::Square:
            return mul(c(2.0), a);
        case Op::PowInt:
            return imm == 0.0 ? c(0.0) : mul(c(imm), unary(Op::PowInt, a, imm - 1.0));
        case Op::Sqrt:
            return div(c(0.5), r);
        case Op::Cbrt:
            return div(c(1.0), mul(c(3.0), square(r)));
        case Op::Abs:
            return unary(Op::Sgn, a);
        case Op::Exp:
            return r;
        case Op::Ln:
            return div(c(1.0), a);
        case Op::Log10:
            return div(c(1.0), mul(a, c(std::numbers::ln10)));
        case Op::Log2:
            return div(c(1.0), mul(a, c(std::numbers::ln2)));
        case Op::Sin:
            return unary(Op::Cos, a);
        case Op::Cos:
            return unary(Op::Neg, unary(Op::Sin, a));
        case Op::Tan:
            return binary(Op::Add, c(1.0), square(r));
        case Op::Asin:
            return div(c(1.0), unary(Op::Sqrt, binary(Op::Sub, c(1.0), square(a))));
        case Op::Acos:
            return div(c(-1.0), unary(Op::Sqrt, binary(Op::Sub, c(1.0), square(a))));
        case Op::Atan:
            return div(c(1.0), binary(Op::Add, c(1.0), square(a)));
        case Op::Sinh:
            return unary(Op::Cosh, a);
        case Op::Cosh:
            return unary(Op::Sinh, a);
        case Op::Tanh:
            return binary(Op::Sub, c(1.0), square(r));
        default:
            return c(0.0);  // sgn, floor, ceil, round: zero wherever differentiable
    }
}

template <class T>
struct Partials {
    T da, db;
};

/// hypot's partial derivatives (a / r, b / r) at a point, 0 where r = 0 (the norm's kink, where
/// 0 is in its generalised gradient, as abs's sgn(0) = 0).
inline Partials<double> norm_partials(double a, double b, double r) {
    if (r == 0.0) return {0.0, 0.0};
    return {a / r, b / r};
}

/// Over a box: each the exact range of its coordinate of the unit vector (a, b) / r
/// (interval_ranges::norm_direction), not [a] / [r], which counts a and r as unrelated.
inline Partials<IntervalValue> norm_partials(const IntervalValue& a, const IntervalValue& b,
                                             const IntervalValue&) {
    return {{interval_ranges::norm_direction(a.value, b.value), false, false},
            {interval_ranges::norm_direction(b.value, a.value), false, false}};
}

/// (d op(a, b) / da, d op(a, b) / db) for the arithmetic operations (not the choice operations
/// min, max and logsumexp), from the operands and the result r = op(a, b).
template <class T>
Partials<T> binary_partials(Op op, const T& a, const T& b, const T& r) {
    auto c = [](double v) { return constant<T>(v); };
    auto neg = [](const T& x) { return unary(Op::Neg, x); };
    auto div = [](const T& x, const T& y) { return binary(Op::Div, x, y); };
    switch (op) {
        case Op::Add:
            return {c(1.0), c(1.0)};
        case Op::Sub:
            return {c(1.0), c(-1.0)};
        case Op::Mul:
            return {b, a};
        case Op::Div:
            return {div(c(1.0), b), neg(div(r, b))};
        case Op::Pow:
            return {binary(Op::Mul, b, binary(Op::Pow, a, binary(Op::Sub, b, c(1.0)))),
                    binary(Op::Mul, r, unary(Op::Ln, a))};
        case Op::Atan2: {
            T norm = binary(Op::Add, unary(Op::Square, a), unary(Op::Square, b));
            return {div(b, norm), neg(div(a, norm))};
        }
        case Op::Hypot:
            return norm_partials(a, b, r);
        default:
            assert(!"min, max and logsumexp select or blend gradients instead");
            return {c(0.0), c(0.0)};
    }
}

/// Which operand's gradient a choice operation (min, max, logsumexp) takes.
enum class Pick { A, B, Either };

/// At a point: for min and max the operand apply_binary returns (b on ties, as a < b ? a : b
/// does); for logsumexp the operand log_sum_exp returns unchanged, beyond kLogSumExpCutoff.
inline Pick pick(Op op, double a, double b) {
    if (op == Op::LogSumExp && !(std::fabs(a - b) > kLogSumExpCutoff)) return Pick::Either;
    return (op == Op::Min ? a < b : a > b) ? Pick::A : Pick::B;
}

/// Over a box: the operand that is returned at every point, when the intervals prove it.
inline Pick pick(Op op, const IntervalValue& a, const IntervalValue& b) {
    const Interval& x = a.value;
    const Interval& y = b.value;
    if (x.is_empty() || y.is_empty()) return Pick::Either;
    if (always_wins(op, x, y)) return Pick::A;
    if (always_wins(op, y, x)) return Pick::B;
    return Pick::Either;
}

inline double either(double a, double) {
    return a;
}
inline IntervalValue either(const IntervalValue& a, const IntervalValue& b) {
    return {hull(a.value, b.value), a.maybe_discontinuous || b.maybe_discontinuous,
            a.maybe_undefined || b.maybe_undefined};
}

/// logsumexp's partial derivatives at a point, the weights exp(a) / (exp(a) + exp(b)) and
/// exp(b) / (exp(a) + exp(b)), from t = exp(-|a - b|) <= 1 (no overflow).
inline Partials<double> log_sum_exp_weights(double a, double b) {
    if (a == b) return {0.5, 0.5};  // also for equal infinities
    const double t = std::exp(-std::fabs(a - b));
    const double larger = 1.0 / (1.0 + t), smaller = t / (1.0 + t);
    return a > b ? Partials<double>{larger, smaller} : Partials<double>{smaller, larger};
}

/// The derivative of logsumexp where neither operand wins outright (pick() is Either): at a
/// point, the product rule with log_sum_exp_weights.
inline double blend(double a, double b, double ga, double gb) {
    const Partials<double> w = log_sum_exp_weights(a, b);
    return term(w.da, ga) + term(w.db, gb);
}

/// Over a box: w ga + (1 - w) gb for a weight w in log_sum_exp_weight (interval_ranges.h), a
/// convex combination. The product rule would treat w and 1 - w as unrelated and give up to twice
/// the hull of ga and gb; this is within the hull, and near one operand's where w is near 0 or 1.
/// For fixed w the extremes are at the ends of ga and gb, and each is linear in w, so at the ends
/// of w. The slack covers the rounding of these formulas and of the point's weights, which sum to
/// 1 within a few ulps.
inline IntervalValue blend(const IntervalValue& a, const IntervalValue& b, const IntervalValue& ga,
                           const IntervalValue& gb) {
    const Interval w = interval_ranges::log_sum_exp_weight(a.value, b.value);
    const Interval& g = ga.value;
    const Interval& h = gb.value;
    const bool discontinuous = ga.maybe_discontinuous || gb.maybe_discontinuous;
    const bool undefined = ga.maybe_undefined || gb.maybe_undefined;
    if (!(std::isfinite(g.lo) && std::isfinite(g.hi) && std::isfinite(h.lo) &&
          std::isfinite(h.hi) && g.lo <= g.hi && h.lo <= h.hi)) {
        const IntervalValue wa{w, false, false}, wb{{1.0 - w.hi, 1.0 - w.lo}, false, false};
        return binary(Op::Add, term(wa, ga), term(wb, gb));
    }
    const double lo = std::min(h.lo + w.lo * (g.lo - h.lo), h.lo + w.hi * (g.lo - h.lo));
    const double hi = std::max(h.hi + w.lo * (g.hi - h.hi), h.hi + w.hi * (g.hi - h.hi));
    const double slack = interval_ranges::kLibmSlack * (std::max(std::fabs(g.lo), std::fabs(g.hi)) +
                                                        std::max(std::fabs(h.lo), std::fabs(h.hi)));
    return {{lo - slack, hi + slack}, discontinuous, undefined};
}

/// A value with its gradient.
template <class T>
struct Tangent {
    T value;
    T grad[3];
};

/// out = the tangent of one unary or binary instruction `op` (immediate `imm`) from its operands'
/// (b is ignored for a unary operation). Written in place: `out` must not be a or b.
template <class T>
[[gnu::always_inline]] inline void step(Tangent<T>& out, Op op, double imm, const Tangent<T>& a,
                                        const Tangent<T>& b) {
    if (is_unary(op)) {
        out.value = unary(op, a.value, imm);
        T partial = unary_partial(op, a.value, out.value, imm);
        for (int k = 0; k < 3; ++k) out.grad[k] = term(partial, a.grad[k]);
        return;
    }
    out.value = binary(op, a.value, b.value);
    if (is_choice(op)) {
        Pick p = pick(op, a.value, b.value);
        for (int k = 0; k < 3; ++k) {
            out.grad[k] = p == Pick::A          ? a.grad[k]
                          : p == Pick::B        ? b.grad[k]
                          : op == Op::LogSumExp ? blend(a.value, b.value, a.grad[k], b.grad[k])
                                                : either(a.grad[k], b.grad[k]);
        }
        return;
    }
    Partials<T> partial = binary_partials(op, a.value, b.value, out.value);
    for (int k = 0; k < 3; ++k)
        out.grad[k] = binary(Op::Add, term(partial.da, a.grad[k]), term(partial.db, b.grad[k]));
}

/// Runs `code` in forward mode and returns the tangent of its last instruction. `leaf(ins)` gives
/// the value of a leaf instruction (constants and variables; parameters are bound to constants).
/// `slots` is scratch memory, resized as needed.
template <class T, class Leaf>
Tangent<T> differentiate(std::span<const Instruction> code, std::vector<Tangent<T>>& slots,
                         const Leaf& leaf) {
    assert(!code.empty());
    if (slots.size() < code.size()) slots.resize(code.size());
    const T zero = constant<T>(0.0), one = constant<T>(1.0);
    for (std::size_t i = 0; i < code.size(); ++i) {
        const Instruction& ins = code[i];
        Tangent<T>& out = slots[i];
        if (is_leaf(ins.op)) {
            out.value = leaf(ins);
            for (int k = 0; k < 3; ++k) out.grad[k] = zero;
            if (ins.op >= Op::VarX && ins.op <= Op::VarZ)
                out.grad[static_cast<int>(ins.op) - 1] = one;
            continue;
        }
        step(out, ins.op, ins.imm, slots[ins.a], slots[is_binary(ins.op) ? ins.b : ins.a]);
    }
    return slots[code.size() - 1];
}

}  // namespace isomesh::forward_mode
