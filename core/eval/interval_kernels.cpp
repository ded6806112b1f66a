// The interval kernels. Every formula below is checked against the reference code it replaces
// (interval_ranges.h for values, forward_mode.h for derivatives); the comments say why the two
// agree bit for bit on finite operands, signed zeros included.
//
// The formulas are written once over a lane type D (double, or a vector of W doubles) and its mask
// type M (the result of comparing two D: bool for double, a vector of W integers, -1 or 0, for a
// vector); `m ? a : b` selects lane by lane for both.
#include "eval/interval_kernels.h"

#include "eval/forward_mode.h"
#include "eval/interval_ranges.h"
#include "eval/lane_types.h"
#include "eval/step_dispatch.h"

namespace isomesh {

namespace {

using namespace lanes;
using lanes::nonfinite;  // overloaded below for intervals
static_assert(kIntervalLanes % kChunk == 0 && kIntervalFewLanes == kChunk);

/// An interval over all lanes.
template <class D>
struct Ends {
    D lo;
    D hi;
};

template <class D>
ISOMESH_KERNEL auto nonfinite(const Ends<D>& e) {
    return nonfinite(e.lo) | nonfinite(e.hi);
}

// std::min(acc, v) and std::max(acc, v), which is how hull() folds values in (ties keep acc, so
// zeros keep their sign as in the reference).
template <class D>
ISOMESH_KERNEL D fold_min(const D& acc, const D& v) {
    return v < acc ? v : acc;
}
template <class D>
ISOMESH_KERNEL D fold_max(const D& acc, const D& v) {
    return acc < v ? v : acc;
}

/// interval_ranges::corners: the hull of the four corner values, folded in the same order.
template <class D>
ISOMESH_KERNEL Ends<D> hull4(const D& p0, const D& p1, const D& p2, const D& p3) {
    return {fold_min(fold_min(fold_min(p0, p1), p2), p3),
            fold_max(fold_max(fold_max(p0, p1), p2), p3)};
}

/// a * b: the reference's corners when no product is 0 * inf, which finite operands rule out.
template <class D>
ISOMESH_KERNEL Ends<D> mul(const Ends<D>& a, const Ends<D>& b) {
    return hull4(a.lo * b.lo, a.lo * b.hi, a.hi * b.lo, a.hi * b.hi);
}

/// a / b for b not containing 0 (the caller checks; the reference returns the entire line then).
template <class D>
ISOMESH_KERNEL Ends<D> div(const Ends<D>& a, const Ends<D>& b) {
    return hull4(a.lo / b.lo, a.lo / b.hi, a.hi / b.lo, a.hi / b.hi);
}

template <class D>
ISOMESH_KERNEL Ends<D> add(const Ends<D>& a, const Ends<D>& b) {
    return {a.lo + b.lo, a.hi + b.hi};
}

/// interval_ranges::magnitude, without branches.
template <class D>
ISOMESH_KERNEL Ends<D> magnitude(const Ends<D>& a) {
    const D zero{};
    const auto nonnegative = a.lo >= zero;
    const auto nonpositive = a.hi <= zero;
    const D straddling_hi = -a.lo < a.hi ? a.hi : -a.lo;  // std::max(-a.lo, a.hi)
    return {nonnegative   ? a.lo
            : nonpositive ? -a.hi
                          : zero,
            nonnegative   ? a.hi
            : nonpositive ? -a.lo
                          : straddling_hi};
}

template <class D>
ISOMESH_KERNEL auto is_zero(const Ends<D>& d) {
    return mask_of(d.lo == D{}) & mask_of(d.hi == D{});
}

/// forward_mode::term(partial, d) for finite operands: exactly 0 for a zero tangent, else the
/// product. The reference then takes the hull with 0 when d contains 0, which changes no bit: the
/// corner products of a finite partial and a d holding 0 include one <= 0 and one >= 0.
template <class D>
ISOMESH_KERNEL Ends<D> term(const Ends<D>& partial, const Ends<D>& d) {
    const Ends<D> t = mul(partial, d);
    const auto zero = is_zero(d);
    return {zero ? D{} : t.lo, zero ? D{} : t.hi};
}

/// term([1, 1], d): the corners are d's ends, folded back to d.
template <class D>
ISOMESH_KERNEL Ends<D> term_one(const Ends<D>& d) {
    const auto zero = is_zero(d);
    return {zero ? D{} : d.lo, zero ? D{} : d.hi};
}

/// term([-1, -1], d): the corners are -d's ends (equal ends are equal bits unless both are zero).
template <class D>
ISOMESH_KERNEL Ends<D> term_minus_one(const Ends<D>& d) {
    const auto zero = is_zero(d);
    return {zero ? D{} : -d.hi, zero ? D{} : -d.lo};
}

/// pow_int(x, k) of op_math.h in every lane: the same multiplications in the same order.
template <class D>
ISOMESH_KERNEL D pow_lanes(const D& x, unsigned k, const D& one) {
    D result = one, base = x;
    while (k != 0) {
        if (k & 1u) result *= base;
        base *= base;
        k >>= 1u;
    }
    return result;
}

/// interval_ranges::pow_int_range for a positive exponent n (no division, no flags).
template <class D>
ISOMESH_KERNEL Ends<D> pow_int_ends(const Ends<D>& a, unsigned n, const D& one) {
    if (n % 2 == 0) {
        const Ends<D> m = magnitude(a);
        return {pow_lanes(m.lo, n, one), pow_lanes(m.hi, n, one)};
    }
    return {pow_lanes(a.lo, n, one), pow_lanes(a.hi, n, one)};
}

/// std::sqrt in every lane (a vector has no square root of its own here).
template <class D>
ISOMESH_KERNEL D sqrt_lanes(const D& x) {
    if constexpr (std::is_arithmetic_v<D>) {
        return std::sqrt(x);
    } else {
        D r;
        for (std::size_t l = 0; l < sizeof(D) / sizeof(double); ++l) r[l] = std::sqrt(x[l]);
        return r;
    }
}

/// A value's enclosures and flags over all lanes.
template <class D, class M>
struct Value {
    Ends<D> ends;
    M flags;
};

/// The reference's IntervalValue of lane l.
template <class D, class M>
ISOMESH_KERNEL IntervalValue lane_value(const Ends<D>& e, const M& flags, std::size_t l) {
    const std::int64_t f = lane(flags, l);
    return {
        {lane(e.lo, l), lane(e.hi, l)}, (f & kMaybeDiscontinuous) != 0, (f & kMaybeUndefined) != 0};
}

/// Lane values computed one lane at a time (by the reference code), gathered into lane values.
template <std::size_t V>
struct LaneResults {
    double lo[V];
    double hi[V];
    std::int64_t flags[V];

    ISOMESH_MEMBER void set(std::size_t l, const IntervalValue& x) {
        lo[l] = x.value.lo;
        hi[l] = x.value.hi;
        flags[l] = (x.maybe_discontinuous ? kMaybeDiscontinuous : 0) |
                   (x.maybe_undefined ? kMaybeUndefined : 0);
    }
    template <class D>
    ISOMESH_MEMBER Ends<D> ends() const {
        return {load<D>(lo), load<D>(hi)};
    }
    template <class D, class M>
    ISOMESH_MEMBER Value<D, M> value() const {
        return {ends<D>(), load<M>(flags)};
    }
};

/// Unary `op` over all lanes: the common operations by formulas exact on finite operands, the
/// others lane by lane with the reference code itself (inlined for `op`).
template <std::size_t W, Op op, class D, class M>
ISOMESH_KERNEL Value<D, M> unary_value(const Ends<D>& a, const M& flags, double imm) {
    using L = LaneTypes<W>;
    if constexpr (op == Op::Neg) {
        return {{-a.hi, -a.lo}, flags};
    } else if constexpr (op == Op::Square) {
        const Ends<D> m = magnitude(a);
        return {{m.lo * m.lo, m.hi * m.hi}, flags};
    } else if constexpr (op == Op::Abs) {
        return {magnitude(a), flags};
    } else if (op == Op::PowInt && imm > 0.0) {  // negative exponents divide: the reference's
        return {pow_int_ends(a, static_cast<unsigned>(imm), L::splat(1.0)), flags};
    } else if constexpr (op == Op::Sqrt) {
        // restrict_to(a, 0, inf) then increasing(): a negative part is undefined; an entirely
        // negative a gives sqrt(a.hi) = NaN, a lane the reference recomputes (as empty).
        const auto negative_part = a.lo < D{};
        const Ends<D> r{negative_part ? D{} : a.lo, a.hi};  // std::max(a.lo, 0.0)
        LaneResults<W> roots;
        for (std::size_t l = 0; l < W; ++l) {
            roots.lo[l] = std::sqrt(lane(r.lo, l));
            roots.hi[l] = std::sqrt(lane(r.hi, l));
        }
        return {roots.template ends<D>(),
                flags | (as_mask<M>(negative_part) & L::splat_mask(kMaybeUndefined))};
    } else {
        LaneResults<W> r;
        for (std::size_t l = 0; l < W; ++l)
            r.set(l, interval_ranges::unary(op, lane_value(a, flags, l), imm));
        return r.template value<D, M>();
    }
}

/// Binary `op` over all lanes, as unary_value. A division by an interval holding 0 is the
/// caller's to recompute with the reference code.
template <std::size_t W, Op op, class D, class M>
ISOMESH_KERNEL Value<D, M> binary_value(const Ends<D>& a, const M& fa, const Ends<D>& b,
                                        const M& fb) {
    const M flags = fa | fb;
    if constexpr (op == Op::Add) {
        return {add(a, b), flags};
    } else if constexpr (op == Op::Sub) {
        return {{a.lo - b.hi, a.hi - b.lo}, flags};  // x + (-y) is x - y, bit for bit
    } else if constexpr (op == Op::Mul) {
        return {mul(a, b), flags};
    } else if constexpr (op == Op::Div) {
        return {div(a, b), flags};
    } else if constexpr (op == Op::Min) {
        return {{fold_min(a.lo, b.lo), fold_min(a.hi, b.hi)}, flags};
    } else if constexpr (op == Op::Max) {
        return {{fold_max(a.lo, b.lo), fold_max(a.hi, b.hi)}, flags};
    } else if constexpr (op == Op::Hypot) {
        // interval_ranges::hypot_range: euclidean_norm of the smallest and of the largest
        // magnitudes, the same operations.
        const Ends<D> ma = magnitude(a), mb = magnitude(b);
        return {
            {sqrt_lanes(ma.lo * ma.lo + mb.lo * mb.lo), sqrt_lanes(ma.hi * ma.hi + mb.hi * mb.hi)},
            flags};
    } else {
        LaneResults<W> r;
        for (std::size_t l = 0; l < W; ++l)
            r.set(l, interval_ranges::binary(op, lane_value(a, fa, l), lane_value(b, fb, l)));
        return r.template value<D, M>();
    }
}

/// What a min or max proves (prove_choice, on finite operands), and which operand's gradient it
/// passes on (forward_mode::pick): a_wins and b_wins.
template <Op op, class D>
ISOMESH_KERNEL auto a_wins(const Ends<D>& a, const Ends<D>& b) {
    if constexpr (op == Op::Min)
        return a.hi < b.lo;
    else
        return a.lo > b.hi;
}

template <std::size_t W, Op op, class D, class M>
ISOMESH_KERNEL void record_choice(const Ends<D>& a, const M& fa, const Ends<D>& b, const M& fb,
                                  Choice* choice, std::size_t stride) {
    using L = LaneTypes<W>;
    const M undefined = L::splat_mask(kMaybeUndefined);
    const M a_proven = as_mask<M>(a_wins<op>(a, b)) & as_mask<M>((fb & undefined) == M{});
    const M b_proven = as_mask<M>(a_wins<op>(b, a)) & as_mask<M>((fa & undefined) == M{});
    for (std::size_t l = 0; l < W; ++l) {
        choice[l * stride] = lane(a_proven, l)   ? Choice::A
                             : lane(b_proven, l) ? Choice::B
                                                 : Choice::Both;
    }
}

/// A register flag bit internal to the kernels: some value or gradient enclosure of the register
/// is not finite in the lane. The steps reading it recompute that lane with the reference code.
constexpr std::int64_t kNotFinite = 4;

/// V lanes of the register file, from lane `offset` on.
template <std::size_t V, class Register>
struct Lanes {
    using D = typename LaneTypes<V>::D;
    using M = typename LaneTypes<V>::M;
    Register* registers;
    std::size_t offset;
    std::size_t by_reference;  // lane-steps recomputed by the reference code

    ISOMESH_MEMBER Ends<D> ends(std::uint32_t r) const {
        return {load<D>(registers[r].lo + offset), load<D>(registers[r].hi + offset)};
    }
    ISOMESH_MEMBER M flags(std::uint32_t r) const { return load<M>(registers[r].flags + offset); }
    /// Stores a value with its flags, kNotFinite set where its ends (or `more`) are not finite.
    template <class Mask>
    ISOMESH_MEMBER void store_value(std::uint32_t r, const Value<D, M>& v, const Mask& more) {
        store(registers[r].lo + offset, v.ends.lo);
        store(registers[r].hi + offset, v.ends.hi);
        const M not_finite = as_mask<M>(nonfinite(v.ends) | more);
        store(registers[r].flags + offset, (v.flags & LaneTypes<V>::splat_mask(~kNotFinite)) |
                                               (not_finite & LaneTypes<V>::splat_mask(kNotFinite)));
    }
    ISOMESH_MEMBER void store_value(std::uint32_t r, const Value<D, M>& v) {
        store_value(r, v, M{});
    }
    /// Sets lane l of register r to the reference's value.
    ISOMESH_MEMBER void set_lane(std::uint32_t r, std::size_t l, const IntervalValue& v,
                                 bool more_not_finite = false) {
        Register& out = registers[r];
        out.lo[offset + l] = v.value.lo;
        out.hi[offset + l] = v.value.hi;
        const bool not_finite = !std::isfinite(v.value.lo) || !std::isfinite(v.value.hi);
        out.flags[offset + l] = (v.maybe_discontinuous ? kMaybeDiscontinuous : 0) |
                                (v.maybe_undefined ? kMaybeUndefined : 0) |
                                (not_finite || more_not_finite ? kNotFinite : 0);
    }

    /// An operand of a binary step: its register, or the immediate as the interval [c, c]
    /// (interval_constant of a finite c) with no flags.
    template <bool in_register>
    ISOMESH_MEMBER Ends<D> operand(std::uint32_t r, double imm) const {
        if constexpr (in_register) return ends(r);
        const D c = LaneTypes<V>::splat(imm);
        return {c, c};
    }
    template <bool in_register>
    ISOMESH_MEMBER M operand_flags(std::uint32_t r) const {
        if constexpr (in_register) return flags(r);
        return M{};
    }
    template <bool in_register>
    ISOMESH_MEMBER IntervalValue operand_value(std::uint32_t r, double imm, std::size_t l) const {
        if constexpr (in_register) {
            const std::int64_t f = registers[r].flags[offset + l];
            return {{registers[r].lo[offset + l], registers[r].hi[offset + l]},
                    (f & kMaybeDiscontinuous) != 0,
                    (f & kMaybeUndefined) != 0};
        }
        return interval_constant(imm);
    }
};

/// Lanes whose operands hold a value that is not finite (nonzero there).
template <class M>
ISOMESH_KERNEL M not_finite_operands(const M& fa, const M& fb) {
    M bit{};
    bit += kNotFinite;
    return (fa | fb) & bit;
}

/// Whether the fast formula of unary `op` (unary_value) covers finite operands in every case; the
/// others run the reference code lane by lane anyway.
template <Op op>
constexpr bool fast_unary(double imm) {
    return op == Op::Neg || op == Op::Square || op == Op::Abs || op == Op::Sqrt ||
           (op == Op::PowInt && imm > 0.0);
}

template <Op op>
constexpr bool fast_binary() {
    return op != Op::Pow && op != Op::Atan2;
}

/// A Const step's value: interval_constant(c) in every lane.
template <std::size_t W>
ISOMESH_KERNEL auto constant_value(double c) {
    LaneResults<W> r;
    for (std::size_t l = 0; l < W; ++l) r.set(l, interval_constant(c));
    return r.template value<typename LaneTypes<W>::D, typename LaneTypes<W>::M>();
}

/// Lanes where the fast formula of unary `op` differs from the reference on finite operands
/// (a square root of an entirely negative interval is empty).
template <Op op, class D>
ISOMESH_KERNEL auto special_unary_operand(const Ends<D>& a) {
    if constexpr (op == Op::Sqrt)
        return a.hi < D{};
    else
        return a.hi != a.hi;  // never, for a finite operand
}

/// Lanes where a division's divisor holds 0 (the reference returns the entire line).
template <class D>
ISOMESH_KERNEL auto holds_zero(const Ends<D>& b) {
    return mask_of(b.lo <= D{}) & mask_of(b.hi >= D{});
}

/// One step of the interval evaluator over V lanes of the register file: the fast formulas for
/// every lane, then the reference code for the lanes where they may differ from it.
template <std::size_t V, class Register>
struct IntervalStep {
    using D = typename LaneTypes<V>::D;
    using M = typename LaneTypes<V>::M;
    const BatchStep& s;
    Lanes<V, Register>& lanes;
    Choice* choice;  // this step's, for the first of the V lanes (a min or max)
    std::size_t choice_stride;

    ISOMESH_MEMBER void constant() { lanes.store_value(s.out, constant_value<V>(s.imm)); }
    ISOMESH_MEMBER void variable() {
        lanes.store_value(s.out, {lanes.ends(s.a), lanes.flags(s.a)});
    }

    template <Op op>
    ISOMESH_MEMBER void unary() {
        const Ends<D> a = lanes.ends(s.a);
        const M fa = lanes.flags(s.a);
        lanes.store_value(s.out, unary_value<V, op>(a, fa, s.imm));
        if (!fast_unary<op>(s.imm)) return;
        const M special = not_finite_operands(fa, M{}) | as_mask<M>(special_unary_operand<op>(a));
        if (!any(special)) return;
        for (std::size_t l = 0; l < V; ++l) {
            if (!lane(special, l)) continue;
            ++lanes.by_reference;
            lanes.set_lane(
                s.out, l,
                interval_ranges::unary(op, lanes.template operand_value<true>(s.a, 0, l), s.imm));
        }
    }

    template <Op op, BatchForm form>
    ISOMESH_MEMBER void binary() {
        constexpr bool a_in_register = form != BatchForm::ImmediateA;
        constexpr bool b_in_register = form != BatchForm::ImmediateB;
        const Ends<D> a = lanes.template operand<a_in_register>(s.a, s.imm);
        const Ends<D> b = lanes.template operand<b_in_register>(s.b, s.imm);
        const M fa = lanes.template operand_flags<a_in_register>(s.a);
        const M fb = lanes.template operand_flags<b_in_register>(s.b);
        if constexpr (op == Op::LogSumExp) {
            // No lane formula: the reference code lane by lane, choices included.
            for (std::size_t l = 0; l < V; ++l) {
                const IntervalValue x = lanes.template operand_value<a_in_register>(s.a, s.imm, l);
                const IntervalValue y = lanes.template operand_value<b_in_register>(s.b, s.imm, l);
                lanes.set_lane(s.out, l, interval_ranges::binary(op, x, y));
                choice[l * choice_stride] = prove_choice(op, x, y);
            }
            return;
        }
        lanes.store_value(s.out, binary_value<V, op>(a, fa, b, fb));
        if constexpr (op == Op::Min || op == Op::Max)
            record_choice<V, op>(a, fa, b, fb, choice, choice_stride);
        if constexpr (!fast_binary<op>()) return;
        M special = not_finite_operands(fa, fb);
        if constexpr (op == Op::Div) special |= as_mask<M>(holds_zero(b));
        if (!any(special)) return;
        for (std::size_t l = 0; l < V; ++l) {
            if (!lane(special, l)) continue;
            ++lanes.by_reference;
            const IntervalValue x = lanes.template operand_value<a_in_register>(s.a, s.imm, l);
            const IntervalValue y = lanes.template operand_value<b_in_register>(s.b, s.imm, l);
            lanes.set_lane(s.out, l, interval_ranges::binary(op, x, y));
            if constexpr (op == Op::Min || op == Op::Max)
                choice[l * choice_stride] = prove_choice(op, x, y);
        }
    }
};

/// One step of the interval forward-mode evaluator over V lanes of the register file: the value
/// as IntervalStep computes it, each gradient component from the partial derivatives of
/// forward_mode.h, then forward_mode::step itself for the lanes where the fast formulas may
/// differ from it.
template <std::size_t V, class Register>
struct GradientStep {
    using D = typename LaneTypes<V>::D;
    using M = typename LaneTypes<V>::M;
    const BatchStep& s;
    Lanes<V, Register>& lanes;
    Choice* choice;
    std::size_t choice_stride;

    template <bool in_register>
    ISOMESH_MEMBER Ends<D> gradient(std::uint32_t r, int k) const {
        if constexpr (in_register)
            return {load<D>(lanes.registers[r].grad_lo[k] + lanes.offset),
                    load<D>(lanes.registers[r].grad_hi[k] + lanes.offset)};
        return {D{}, D{}};
    }

    /// Stores the value and the gradient, and returns the lanes where a gradient is NaN (a sum of
    /// infinities of both signs, which the reference's addition turns into infinities).
    ISOMESH_MEMBER M store(const Value<D, M>& v, const Ends<D> (&g)[3]) {
        Register& out = lanes.registers[s.out];
        M not_finite{}, nan{};
        for (int k = 0; k < 3; ++k) {
            lanes::store(out.grad_lo[k] + lanes.offset, g[k].lo);
            lanes::store(out.grad_hi[k] + lanes.offset, g[k].hi);
            not_finite |= as_mask<M>(nonfinite(g[k]));
            nan |= as_mask<M>(mask_of(g[k].lo != g[k].lo) | mask_of(g[k].hi != g[k].hi));
        }
        lanes.store_value(s.out, v, not_finite);
        return nan;
    }

    template <bool in_register>
    ISOMESH_MEMBER forward_mode::Tangent<IntervalValue> operand_tangent(std::uint32_t r,
                                                                        std::size_t l) const {
        forward_mode::Tangent<IntervalValue> t;
        t.value = lanes.template operand_value<in_register>(r, s.imm, l);
        for (int k = 0; k < 3; ++k) {
            if constexpr (in_register) {
                const std::size_t i = lanes.offset + l;
                t.grad[k] = {{lanes.registers[r].grad_lo[k][i], lanes.registers[r].grad_hi[k][i]},
                             false,
                             false};  // gradient flags never reach an enclosure
            } else {
                t.grad[k] = interval_constant(0.0);
            }
        }
        return t;
    }

    /// Recomputes the special lanes with forward_mode::step (`counted`: as lane-steps left to the
    /// reference, rather than an operation without lane formulas).
    template <Op op, bool a_in_register, bool b_in_register, bool counted = true>
    ISOMESH_MEMBER void recompute(const M& special) {
        if (!any(special)) return;
        for (std::size_t l = 0; l < V; ++l) {
            if (!lane(special, l)) continue;
            if constexpr (counted) ++lanes.by_reference;
            const auto a = operand_tangent<a_in_register>(s.a, l);
            const auto b = operand_tangent<b_in_register>(s.b, l);
            forward_mode::Tangent<IntervalValue> t;
            forward_mode::step(t, op, s.imm, a, b);
            Register& out = lanes.registers[s.out];
            const std::size_t i = lanes.offset + l;
            bool gradient_not_finite = false;
            for (int k = 0; k < 3; ++k) {
                out.grad_lo[k][i] = t.grad[k].value.lo;
                out.grad_hi[k][i] = t.grad[k].value.hi;
                gradient_not_finite |=
                    !std::isfinite(t.grad[k].value.lo) || !std::isfinite(t.grad[k].value.hi);
            }
            lanes.set_lane(s.out, l, t.value, gradient_not_finite);
            if constexpr (is_choice(op))
                choice[l * choice_stride] = prove_choice(op, a.value, b.value);
        }
    }

    ISOMESH_MEMBER void constant() {
        const Ends<D> zero[3] = {{D{}, D{}}, {D{}, D{}}, {D{}, D{}}};
        store(constant_value<V>(s.imm), zero);
    }
    ISOMESH_MEMBER void variable() {
        const Ends<D> g[3] = {gradient<true>(s.a, 0), gradient<true>(s.a, 1),
                              gradient<true>(s.a, 2)};
        store({lanes.ends(s.a), lanes.flags(s.a)}, g);
    }

    template <Op op>
    ISOMESH_MEMBER void unary() {
        const Ends<D> a = lanes.ends(s.a);
        const M fa = lanes.flags(s.a);
        const Value<D, M> r = unary_value<V, op>(a, fa, s.imm);
        const Ends<D> partial = unary_partial<op>(a, fa, r);
        Ends<D> g[3];
        for (int k = 0; k < 3; ++k) {
            const Ends<D> d = gradient<true>(s.a, k);
            g[k] = op == Op::Neg ? term_minus_one(d) : term(partial, d);
        }
        M special = store(r, g) | not_finite_operands(fa, M{}) |
                    as_mask<M>(nonfinite(partial) | special_unary_operand<op>(a));
        if constexpr (op == Op::Ln) special |= as_mask<M>(a.lo <= D{});  // 1 / a's hull
        recompute<op, true, true>(special);
    }

    /// d op(a) / da (forward_mode::unary_partial), by formulas for the common operations.
    template <Op op>
    ISOMESH_MEMBER Ends<D> unary_partial(const Ends<D>& a, const M& fa,
                                         const Value<D, M>& r) const {
        using L = LaneTypes<V>;
        if constexpr (op == Op::Neg) {
            return {L::splat(-1.0), L::splat(-1.0)};  // term_minus_one applies it
        } else if constexpr (op == Op::Square) {
            return mul({L::splat(2.0), L::splat(2.0)}, a);
        } else if constexpr (op == Op::Sqrt) {
            return div({L::splat(0.5), L::splat(0.5)}, r.ends);  // r holding 0: infinite
        } else if (op == Op::PowInt && s.imm > 0.0) {
            // imm * a^(imm - 1), a^0 being [1, 1] as the reference's unary() makes it.
            const auto n = static_cast<unsigned>(s.imm);
            const D one = L::splat(1.0);
            const Ends<D> power = n == 1 ? Ends<D>{one, one} : pow_int_ends(a, n - 1, one);
            return mul({L::splat(s.imm), L::splat(s.imm)}, power);
        } else if constexpr (op == Op::Exp) {
            return r.ends;
        } else if constexpr (op == Op::Ln) {
            return div({L::splat(1.0), L::splat(1.0)}, a);
        } else {
            LaneResults<V> p;
            for (std::size_t l = 0; l < V; ++l) {
                p.set(l, forward_mode::unary_partial(op, lane_value(a, fa, l),
                                                     lane_value(r.ends, r.flags, l), s.imm));
            }
            return p.template ends<D>();
        }
    }

    template <Op op, BatchForm form>
    ISOMESH_MEMBER void binary() {
        using L = LaneTypes<V>;
        constexpr bool a_in_register = form != BatchForm::ImmediateA;
        constexpr bool b_in_register = form != BatchForm::ImmediateB;
        if constexpr (op == Op::LogSumExp) {  // no lane formulas: forward_mode::step per lane
            recompute<op, a_in_register, b_in_register, false>(L::splat_mask(-1));
            return;
        }
        const Ends<D> a = lanes.template operand<a_in_register>(s.a, s.imm);
        const Ends<D> b = lanes.template operand<b_in_register>(s.b, s.imm);
        const M fa = lanes.template operand_flags<a_in_register>(s.a);
        const M fb = lanes.template operand_flags<b_in_register>(s.b);
        const Value<D, M> r = binary_value<V, op>(a, fa, b, fb);
        Ends<D> g[3];
        M special = not_finite_operands(fa, fb);
        if constexpr (op == Op::Min || op == Op::Max) {
            record_choice<V, op>(a, fa, b, fb, choice, choice_stride);
            const auto pick_a = a_wins<op>(a, b);
            const auto pick_b = a_wins<op>(b, a);
            for (int k = 0; k < 3; ++k) {
                const Ends<D> ga = gradient<a_in_register>(s.a, k);
                const Ends<D> gb = gradient<b_in_register>(s.b, k);
                // forward_mode::either: the hull of two finite (so non-empty) intervals.
                const Ends<D> either{fold_min(ga.lo, gb.lo), fold_max(ga.hi, gb.hi)};
                g[k] = {pick_a   ? ga.lo
                        : pick_b ? gb.lo
                                 : either.lo,
                        pick_a   ? ga.hi
                        : pick_b ? gb.hi
                                 : either.hi};
            }
        } else if constexpr (op == Op::Add || op == Op::Sub) {
            for (int k = 0; k < 3; ++k) {
                const Ends<D> gb = gradient<b_in_register>(s.b, k);
                g[k] = add(term_one(gradient<a_in_register>(s.a, k)),
                           op == Op::Add ? term_one(gb) : term_minus_one(gb));
            }
        } else {
            Ends<D> da{}, db{};  // the partial derivatives
            if constexpr (op == Op::Mul) {
                da = b;
                db = a;
            } else if constexpr (op == Op::Div) {
                da = div({L::splat(1.0), L::splat(1.0)}, b);
                const Ends<D> q = div(r.ends, b);
                db = {-q.hi, -q.lo};
                special |= as_mask<M>(holds_zero(b));
            } else if constexpr (op == Op::Hypot) {
                // forward_mode::norm_partials: norm_direction itself, lane by lane.
                double pa_lo[V], pa_hi[V], pb_lo[V], pb_hi[V];
                for (std::size_t l = 0; l < V; ++l) {
                    const Interval x{lane(a.lo, l), lane(a.hi, l)}, y{lane(b.lo, l), lane(b.hi, l)};
                    const Interval u = interval_ranges::norm_direction(x, y);
                    const Interval v = interval_ranges::norm_direction(y, x);
                    pa_lo[l] = u.lo, pa_hi[l] = u.hi, pb_lo[l] = v.lo, pb_hi[l] = v.hi;
                }
                da = {load<D>(pa_lo), load<D>(pa_hi)};
                db = {load<D>(pb_lo), load<D>(pb_hi)};
            } else {
                LaneResults<V> pa, pb;
                for (std::size_t l = 0; l < V; ++l) {
                    const auto p = forward_mode::binary_partials(op, lane_value(a, fa, l),
                                                                 lane_value(b, fb, l),
                                                                 lane_value(r.ends, r.flags, l));
                    pa.set(l, p.da);
                    pb.set(l, p.db);
                }
                da = pa.template ends<D>();
                db = pb.template ends<D>();
            }
            special |= as_mask<M>(nonfinite(da) | nonfinite(db));
            for (int k = 0; k < 3; ++k) {
                g[k] = add(term(da, gradient<a_in_register>(s.a, k)),
                           term(db, gradient<b_in_register>(s.b, k)));
            }
        }
        special |= store(r, g);
        recompute<op, a_in_register, b_in_register>(special);
    }
};

template <std::size_t W, template <std::size_t, class> class Step, class Register>
ISOMESH_KERNEL std::size_t run(std::span<const BatchStep> steps, Register* registers,
                               Choice* choices, std::size_t choice_count) {
    using M = typename LaneTypes<W == 1 ? 1 : kChunk>::M;
    constexpr std::size_t V = W == 1 ? 1 : kChunk;
    constexpr std::size_t kChunks = W / V;
    Lanes<V, Register> chunks[kChunks];
    for (std::size_t c = 0; c < kChunks; ++c) {
        chunks[c] = {registers, c * V, 0};
        for (std::uint32_t r = 0; r < 3; ++r) {  // the box's x, y and z
            M flags = chunks[c].flags(r);
            flags |=
                as_mask<M>(nonfinite(chunks[c].ends(r))) & LaneTypes<V>::splat_mask(kNotFinite);
            store(registers[r].flags + c * V, flags);
        }
    }
    Choice* choice = choices;
    for (const BatchStep& s : steps) {
        struct {
            const BatchStep& s;
            Lanes<V, Register> (&chunks)[kChunks];
            Choice* choice;
            std::size_t stride;
            ISOMESH_MEMBER Step<V, Register> operator()(std::size_t c) const {
                return {s, chunks[c], choice + chunks[c].offset * stride, stride};
            }
        } make{s, chunks, choice, choice_count};
        Chunked<kChunks, decltype(make)> visitor{make};
        dispatch_step(s, visitor);
        if (is_choice(s.op)) ++choice;
    }
    std::size_t by_reference = 0;
    for (const auto& chunk : chunks) by_reference += chunk.by_reference;
    return by_reference;
}

}  // namespace

std::size_t run_interval_steps(std::span<const BatchStep> steps, IntervalRegister<1>* registers,
                               Choice* choices, std::size_t choice_count) {
    return run<1, IntervalStep>(steps, registers, choices, choice_count);
}

ISOMESH_VECTOR_CLONES std::size_t run_interval_steps(std::span<const BatchStep> steps,
                                                     IntervalRegister<kIntervalFewLanes>* registers,
                                                     Choice* choices, std::size_t choice_count) {
    return run<kIntervalFewLanes, IntervalStep>(steps, registers, choices, choice_count);
}

ISOMESH_VECTOR_CLONES std::size_t run_interval_steps(std::span<const BatchStep> steps,
                                                     IntervalRegister<kIntervalLanes>* registers,
                                                     Choice* choices, std::size_t choice_count) {
    return run<kIntervalLanes, IntervalStep>(steps, registers, choices, choice_count);
}

std::size_t run_gradient_steps(std::span<const BatchStep> steps, GradientRegister<1>* registers,
                               Choice* choices, std::size_t choice_count) {
    return run<1, GradientStep>(steps, registers, choices, choice_count);
}

ISOMESH_VECTOR_CLONES std::size_t run_gradient_steps(std::span<const BatchStep> steps,
                                                     GradientRegister<kIntervalFewLanes>* registers,
                                                     Choice* choices, std::size_t choice_count) {
    return run<kIntervalFewLanes, GradientStep>(steps, registers, choices, choice_count);
}

ISOMESH_VECTOR_CLONES std::size_t run_gradient_steps(std::span<const BatchStep> steps,
                                                     GradientRegister<kIntervalLanes>* registers,
                                                     Choice* choices, std::size_t choice_count) {
    return run<kIntervalLanes, GradientStep>(steps, registers, choices, choice_count);
}

}  // namespace isomesh
