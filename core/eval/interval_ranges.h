// The scalar interval arithmetic behind eval/interval_math.h, inline so that the fast evaluators
// (interval_kernels.cpp) run the very same code per lane, specialised to each operation, as the
// reference functions interval_unary and interval_binary. See interval_math.cpp for the rounding
// argument; everything here is internal to eval/.
#pragma once

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <numbers>

#include "eval/interval_math.h"
#include "eval/tape_ops.h"
#include "tape/op_math.h"

namespace isomesh::interval_ranges {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = std::numbers::pi;
constexpr double kLibmSlack = 16 * std::numeric_limits<double>::epsilon();
constexpr double kUnderflowSlack = 16 * std::numeric_limits<double>::denorm_min();

/// What an operation adds to its operands' flags.
struct Effects {
    bool discontinuous = false;
    bool undefined = false;
};

enum class Zero { Exact, Underflow };

inline double widen_down(double v, Zero zero) {
    if (!std::isfinite(v)) return v;
    if (v == 0.0) return zero == Zero::Exact ? v : -kUnderflowSlack;
    return v - std::max(std::fabs(v) * kLibmSlack, kUnderflowSlack);
}

inline double widen_up(double v, Zero zero) {
    return -widen_down(-v, zero);
}

/// Outward widening of an interval of libm results (see the file comment).
inline Interval widen(const Interval& r, Zero zero) {
    return {widen_down(r.lo, zero), widen_up(r.hi, zero)};
}

inline Interval clamp(const Interval& r, double lo, double hi) {
    return {std::max(r.lo, lo), std::min(r.hi, hi)};
}

inline double unary_value(Op op, double v) {
    return apply_unary(op, v, 0.0);
}

/// op over a, for op non-decreasing on a.
inline Interval increasing(Op op, const Interval& a) {
    if (a.is_empty()) return a;
    return {unary_value(op, a.lo), unary_value(op, a.hi)};
}

/// op over a, for op non-increasing on a.
inline Interval decreasing(Op op, const Interval& a) {
    if (a.is_empty()) return a;
    return {unary_value(op, a.hi), unary_value(op, a.lo)};
}

/// {|v| : v in a}.
inline Interval magnitude(const Interval& a) {
    if (a.lo >= 0.0) return a;
    if (a.hi <= 0.0) return {-a.hi, -a.lo};
    return {0.0, std::max(-a.lo, a.hi)};
}

/// a restricted to [lo, hi] (possibly empty); notes when part of a lies outside.
inline Interval restrict_to(const Interval& a, double lo, double hi, Effects& e) {
    if (a.lo < lo || a.hi > hi) e.undefined = true;
    Interval r{std::max(a.lo, lo), std::min(a.hi, hi)};
    return r.is_empty() ? Interval::empty() : r;
}

/// A monotone step function (sgn, floor, ceil, round): constant on a exactly when its values at
/// the two ends agree; otherwise it jumps somewhere inside.
inline Interval step_function(Op op, const Interval& a, Effects& e) {
    Interval r = increasing(op, a);
    if (r.lo != r.hi) e.discontinuous = true;
    return r;
}

/// True when [a.lo, a.hi] may contain phase + k * period for a whole k. Errs towards true: the
/// slack covers the rounding of the reduction, and for huge arguments the answer is always true.
inline bool may_contain_periodic_point(const Interval& a, double phase, double period) {
    double t_lo = (a.lo - phase) / period;
    double t_hi = (a.hi - phase) / period;
    double slack = 1e-9 * std::max({1.0, std::fabs(t_lo), std::fabs(t_hi)});
    return std::floor(t_hi + slack) >= std::ceil(t_lo - slack);
}

/// sin and cos: between extrema they are monotone, so the range is the hull of the end values,
/// extended to +-1 where a maximum or minimum lies inside.
inline Interval sin_cos_range(Op op, const Interval& a, Effects& e) {
    if (!std::isfinite(a.lo) || !std::isfinite(a.hi)) {
        e.undefined = true;  // sin(+-inf) is NaN
        return {-1.0, 1.0};
    }
    if (a.hi - a.lo >= 2 * kPi) return {-1.0, 1.0};
    double shift = op == Op::Sin ? 0.0 : kPi / 2;  // cos(x) = sin(x + pi/2)
    double lo = unary_value(op, a.lo), hi = unary_value(op, a.hi);
    Interval r = widen({std::min(lo, hi), std::max(lo, hi)}, Zero::Exact);
    if (may_contain_periodic_point(a, kPi / 2 - shift, 2 * kPi)) r.hi = 1.0;
    if (may_contain_periodic_point(a, -kPi / 2 - shift, 2 * kPi)) r.lo = -1.0;
    return clamp(r, -1.0, 1.0);
}

/// tan: increasing between its poles at pi/2 + k pi; across a pole, anything.
inline Interval tan_range(const Interval& a, Effects& e) {
    if (!std::isfinite(a.lo) || !std::isfinite(a.hi)) {
        e.undefined = true;
        e.discontinuous = true;
        return Interval::entire();
    }
    if (a.hi - a.lo >= kPi || may_contain_periodic_point(a, kPi / 2, kPi)) {
        e.discontinuous = true;
        return Interval::entire();
    }
    return widen(increasing(Op::Tan, a), Zero::Exact);
}

/// ln, log10, log2: defined on [0, inf] (log(0) = -inf, a pole).
inline Interval log_range(Op op, const Interval& a, Effects& e) {
    Interval d = restrict_to(a, 0.0, kInf, e);
    if (d.is_empty()) return d;
    if (d.lo == 0.0) e.discontinuous = true;
    return widen(increasing(op, d), Zero::Exact);
}

/// The four products or quotients of the endpoints, whose hull bounds an operation monotone in
/// each operand. A NaN corner (0 * inf, inf / inf) is undefined itself; of the values around it,
/// the infinite ones are other corners, but the zeros (0 * finite y, finite x / inf) are not and
/// are added when the interval holding the finite values is not a single point.
inline Interval corners(Op op, const Interval& a, const Interval& b, Effects& e) {
    Interval r = Interval::empty();
    for (double x : {a.lo, a.hi}) {
        for (double y : {b.lo, b.hi}) {
            double v = apply_binary(op, x, y);
            if (std::isnan(v)) {
                e.undefined = true;
                const Interval& finite_side = op == Op::Div || std::isinf(x) ? a : b;
                if (finite_side.lo == finite_side.hi) continue;
                v = 0.0;
            }
            r = hull(r, {v, v});
        }
    }
    return r;
}

inline bool has_infinite_end(const Interval& a) {
    return std::isinf(a.lo) || std::isinf(a.hi);
}

inline Interval multiply_range(const Interval& a, const Interval& b, Effects& e) {
    // 0 * inf is NaN, also for a zero inside an interval (not only at a corner).
    if ((a.contains(0.0) && has_infinite_end(b)) || (b.contains(0.0) && has_infinite_end(a)))
        e.undefined = true;
    return corners(Op::Mul, a, b, e);
}

inline Interval add_range(const Interval& a, const Interval& b, Effects& e) {
    if ((a.lo == -kInf && b.hi == kInf) || (a.hi == kInf && b.lo == -kInf)) e.undefined = true;
    double lo = a.lo + b.lo, hi = a.hi + b.hi;
    if (std::isnan(lo) && std::isnan(hi)) return Interval::empty();  // inf + -inf everywhere
    return {std::isnan(lo) ? -kInf : lo, std::isnan(hi) ? kInf : hi};
}

inline Interval sub_range(const Interval& a, const Interval& b, Effects& e) {
    return add_range(a, {-b.hi, -b.lo}, e);
}

inline Interval divide_range(const Interval& a, const Interval& b, Effects& e) {
    if (b.contains(0.0)) {
        // A pole. The sign of a zero divisor (+0 or -0) is unknown, so both infinities may occur.
        e.discontinuous = true;
        if (a.contains(0.0)) e.undefined = true;                             // 0/0
        if (has_infinite_end(a) && has_infinite_end(b)) e.undefined = true;  // inf/inf
        return Interval::entire();
    }
    return corners(Op::Div, a, b, e);
}

/// pow_int(a, n): products of correctly rounded multiplications, monotone in |a| (no widening);
/// a negative exponent is 1 / pow_int(a, -n), computed exactly so by pow_int.
inline Interval pow_int_range(const Interval& a, int n, Effects& e) {
    assert(n != 0);
    unsigned k = n < 0 ? 0u - static_cast<unsigned>(n) : static_cast<unsigned>(n);
    auto power = [k](double v) { return pow_int(v, static_cast<int>(k)); };
    Interval p;
    if (k % 2 == 0) {
        Interval m = magnitude(a);
        p = {power(m.lo), power(m.hi)};
    } else {
        p = {power(a.lo), power(a.hi)};
    }
    if (n > 0) return p;
    return divide_range({1.0, 1.0}, p, e);
}

inline bool is_whole(double v) {
    return std::isfinite(v) && v == std::trunc(v);
}

/// True when [a.lo, a.hi] contains a whole number (or reaches an infinity).
inline bool contains_whole(const Interval& a) {
    return std::isinf(a.lo) || std::isinf(a.hi) || std::ceil(a.lo) <= std::floor(a.hi);
}

/// std::pow over base x exponent for a non-negative base interval (with +0, never -0): pow is
/// monotone in the base for a fixed exponent and in the exponent for a fixed base, so its extremes
/// are at the corners.
inline Interval pow_corners(const Interval& base, const Interval& exponent) {
    Interval r = Interval::empty();
    for (double x : {base.lo, base.hi}) {
        for (double y : {exponent.lo, exponent.hi}) {
            double v = apply_binary(Op::Pow, x, y);
            r = hull(r, {v, v});
        }
    }
    return clamp(widen(r, Zero::Underflow), 0.0, kInf);
}

/// std::pow: x^y for x >= 0; for x < 0 only whole y give numbers ((-1)^y |x|^y); pow(-0, y) is
/// -inf for a negative odd whole y; pow(NaN, 0) = pow(1, NaN) = 1.
inline IntervalValue pow_interval(const IntervalValue& base, const IntervalValue& exponent) {
    const Interval& x = base.value;
    const Interval& y = exponent.value;
    Effects e;
    Interval r = Interval::empty();
    if (!x.is_empty() && !y.is_empty()) {
        if (x.hi >= 0.0) {
            Interval nonnegative{x.lo > 0.0 ? x.lo : 0.0, x.hi};
            r = pow_corners(nonnegative, y);
            if (nonnegative.lo == 0.0 && y.lo <= 0.0) e.discontinuous = true;  // 0^-y, 0^0
            if (nonnegative.lo == 0.0 && y.lo < 0.0 && contains_whole({y.lo, std::min(y.hi, -1.0)}))
                r.lo = -kInf;  // the base may be -0
        }
        if (x.lo < 0.0) {
            Interval m{x.hi >= 0.0 ? 0.0 : -x.hi, -x.lo};  // |x| over the negative part
            Interval p = pow_corners(m, y);
            if (y.lo == y.hi && is_whole(y.lo)) {
                bool odd = std::fmod(y.lo, 2.0) != 0.0;
                r = hull(r, odd ? Interval{-p.hi, -p.lo} : p);
            } else {
                e.undefined = true;  // non-whole exponents of a negative base
                if (contains_whole(y)) {
                    e.discontinuous = true;
                    r = hull(r, {-p.hi, p.hi});
                }
                if (x.lo == -kInf) r = hull(r, pow_corners({kInf, kInf}, y));  // pow(-inf, y)
            }
        }
    }
    if ((base.maybe_undefined || x.is_empty()) && y.contains(0.0)) r = hull(r, {1.0, 1.0});
    if ((exponent.maybe_undefined || y.is_empty()) && x.contains(1.0)) r = hull(r, {1.0, 1.0});
    bool discontinuous =
        base.maybe_discontinuous || exponent.maybe_discontinuous || e.discontinuous;
    bool undefined = base.maybe_undefined || exponent.maybe_undefined || e.undefined;
    return {r, discontinuous, undefined || r.is_empty()};
}

/// atan2(y, x), the angle of (x, y): continuous except across the negative x axis (where it jumps
/// between pi and -pi) and at the origin. Away from those, the extremes over the box are at its
/// corners.
inline Interval atan2_range(const Interval& y, const Interval& x, Effects& e) {
    static const double kPiUp = std::nextafter(kPi, kInf);
    if (y.contains(0.0) && x.lo <= 0.0) {
        e.discontinuous = true;
        return {-kPiUp, kPiUp};
    }
    return widen(corners(Op::Atan2, y, x, e), Zero::Exact);
}

/// logsumexp: increasing in each operand, so its range is spanned by its values at the lower and
/// at the upper ends. Widened by a slack absolute to the operands' scale: log_sum_exp's error is
/// a few ulps of max(a, b) and of ln 2, not of its result (which may be near 0).
inline Interval log_sum_exp_range(const Interval& a, const Interval& b) {
    const double lo = log_sum_exp(a.lo, b.lo), hi = log_sum_exp(a.hi, b.hi);
    double scale = 1.0;
    for (double v : {lo, hi})
        if (std::isfinite(v)) scale = std::max(scale, std::fabs(v));
    return {lo - kLibmSlack * scale, hi + kLibmSlack * scale};
}

/// The weight of operand a in logsumexp's derivative, exp(a) / (exp(a) + exp(b)) = 1 / (1 +
/// exp(b - a)), over a x b: increasing in a - b, so spanned by the ends of a - b; widened for
/// libm's rounding, within [0, 1]. [0, 1] where a - b is undefined.
inline Interval log_sum_exp_weight(const Interval& a, const Interval& b) {
    if (a.is_empty() || b.is_empty()) return {0.0, 1.0};
    const double d_lo = a.lo - b.hi, d_hi = a.hi - b.lo;
    const double lo = d_lo == d_lo ? 1.0 / (1.0 + std::exp(-d_lo)) : 0.0;
    const double hi = d_hi == d_hi ? 1.0 / (1.0 + std::exp(-d_hi)) : 1.0;
    return clamp({lo - kLibmSlack, hi + kLibmSlack}, 0.0, 1.0);
}

/// hypot: increasing in |a| and in |b|, so its range is spanned by the values at the smallest
/// and at the largest magnitudes (the distance from the origin to the box of (a, b), and to its
/// farthest corner). Its + * sqrt are correctly rounded, so monotone: no widening.
inline Interval hypot_range(const Interval& a, const Interval& b) {
    const Interval ma = magnitude(a), mb = magnitude(b);
    return {euclidean_norm(ma.lo, mb.lo), euclidean_norm(ma.hi, mb.hi)};
}

/// Below this, hypot's squares may be subnormal somewhere on the box, where they round with a
/// large relative error: the point's a / r then strays from u (by at most a factor 1.23 when the
/// sum of squares rounds to a nonzero subnormal, and r = 0 gives 0).
constexpr double kSmallestNormalNorm = 1e-150;
constexpr double kSubnormalDirection = 1.25;

/// The range of u = a / hypot(a, b), the first coordinate of the unit vector along (a, b), over
/// the box a x b: hypot's partial derivative in a (by symmetry, direction(b, a) is the one in b).
/// u is increasing in a (du/da = b^2 / r^3) and, for fixed a, moves away from 0 as |b| shrinks,
/// so its maximum is at a = a.hi with |b| smallest if a.hi >= 0 (largest otherwise), and its
/// minimum at a = a.lo with |b| largest if a.lo >= 0 (smallest otherwise). Widened for the
/// rounding of the point's a / r, which is within a few ulps of u and never beyond [-1, 1] where
/// r is a normal number. Where r may be 0 (the box holds the origin, the norm's kink) or tiny,
/// the point's partial is 0 or a / r of a's sign: [-1, 1] (the generalised gradient at the
/// kink, as abs's [-1, 1] at 0) cut to a's sign, widened for subnormal rounding. Where r may
/// overflow, the point's a / inf is 0 or NaN: a's sign again.
inline Interval norm_direction(const Interval& a, const Interval& b) {
    if (a.is_empty() || b.is_empty()) return {-kSubnormalDirection, kSubnormalDirection};
    const Interval r = hypot_range(a, b);
    if (!(r.lo >= kSmallestNormalNorm) || !(r.hi < kInf)) {
        return {a.lo < 0.0 ? -kSubnormalDirection : 0.0, a.hi > 0.0 ? kSubnormalDirection : 0.0};
    }
    const Interval mb = magnitude(b);
    const double b_for_hi = a.hi >= 0.0 ? mb.lo : mb.hi;
    const double b_for_lo = a.lo >= 0.0 ? mb.hi : mb.lo;
    const double hi = a.hi / euclidean_norm(a.hi, b_for_hi);
    const double lo = a.lo / euclidean_norm(a.lo, b_for_lo);
    return clamp(widen({lo, hi}, Zero::Underflow), -1.0, 1.0);
}

[[gnu::always_inline]] inline Interval unary_range(Op op, const Interval& a, double imm,
                                                   Effects& e) {
    switch (op) {
        case Op::Neg:
            return {-a.hi, -a.lo};
        case Op::Square:
            return increasing(Op::Square, magnitude(a));
        case Op::PowInt:
            return pow_int_range(a, static_cast<int>(imm), e);
        case Op::Sqrt:
            return increasing(Op::Sqrt, restrict_to(a, 0.0, kInf, e));
        case Op::Cbrt:
            return widen(increasing(op, a), Zero::Exact);
        case Op::Abs:
            return magnitude(a);
        case Op::Sgn:
        case Op::Floor:
        case Op::Ceil:
        case Op::Round:
            return step_function(op, a, e);
        case Op::Exp:
            return clamp(widen(increasing(op, a), Zero::Underflow), 0.0, kInf);
        case Op::Ln:
        case Op::Log10:
        case Op::Log2:
            return log_range(op, a, e);
        case Op::Sin:
        case Op::Cos:
            return sin_cos_range(op, a, e);
        case Op::Tan:
            return tan_range(a, e);
        case Op::Asin:
            return widen(increasing(op, restrict_to(a, -1.0, 1.0, e)), Zero::Exact);
        case Op::Acos:
            return clamp(widen(decreasing(op, restrict_to(a, -1.0, 1.0, e)), Zero::Exact), 0.0,
                         kInf);
        case Op::Atan:
        case Op::Sinh:
            return widen(increasing(op, a), Zero::Exact);
        case Op::Cosh:
            return clamp(widen(increasing(op, magnitude(a)), Zero::Exact), 1.0, kInf);
        case Op::Tanh:
            return clamp(widen(increasing(op, a), Zero::Exact), -1.0, 1.0);
        default:
            assert(!"not a unary operation");
            return Interval::entire();
    }
}

[[gnu::always_inline]] inline Interval binary_range(Op op, const Interval& a, const Interval& b,
                                                    Effects& e) {
    switch (op) {
        case Op::Add:
            return add_range(a, b, e);
        case Op::Sub:
            return sub_range(a, b, e);
        case Op::Mul:
            return multiply_range(a, b, e);
        case Op::Div:
            return divide_range(a, b, e);
        case Op::Atan2:
            return atan2_range(a, b, e);
        case Op::Min:
            return {std::min(a.lo, b.lo), std::min(a.hi, b.hi)};
        case Op::Max:
            return {std::max(a.lo, b.lo), std::max(a.hi, b.hi)};
        case Op::LogSumExp:
            return log_sum_exp_range(a, b);
        case Op::Hypot:
            return hypot_range(a, b);
        default:
            assert(!"not a binary operation");
            return Interval::entire();
    }
}

/// interval_unary, inline.
[[gnu::always_inline]] inline IntervalValue unary(Op op, const IntervalValue& a, double imm) {
    assert(is_unary(op));
    if (op == Op::PowInt && static_cast<int>(imm) == 0)
        return {{1.0, 1.0}, false, false};  // x^0 = 1, even for NaN
    if (a.value.is_empty()) return {Interval::empty(), a.maybe_discontinuous, true};
    Effects e;
    Interval r = unary_range(op, a.value, imm, e);
    if (r.is_empty()) r = Interval::empty();
    return {r, a.maybe_discontinuous || e.discontinuous,
            a.maybe_undefined || e.undefined || r.is_empty()};
}

/// interval_binary, inline.
[[gnu::always_inline]] inline IntervalValue binary(Op op, const IntervalValue& a,
                                                   const IntervalValue& b) {
    assert(is_binary(op));
    if (op == Op::Pow) return pow_interval(a, b);
    bool discontinuous = a.maybe_discontinuous || b.maybe_discontinuous;
    if (a.value.is_empty() || b.value.is_empty()) return {Interval::empty(), discontinuous, true};
    Effects e;
    Interval r = binary_range(op, a.value, b.value, e);
    if (r.is_empty()) r = Interval::empty();
    return {r, discontinuous || e.discontinuous,
            a.maybe_undefined || b.maybe_undefined || e.undefined || r.is_empty()};
}

}  // namespace isomesh::interval_ranges
