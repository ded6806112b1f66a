// The interval kernels' shared part: the lane formulas (written once over a lane type D, a double
// or a vector of W doubles, and its mask type M: `m ? a : b` selects lane by lane for both), the
// register lanes a step reads and writes, and the loop that runs a program's steps over W boxes.
// Every formula is checked against the reference code it replaces (interval_ranges.h for values,
// forward_mode.h for derivatives); the comments say why the two agree bit for bit on finite
// operands, signed zeros included.
//
// Internal to the two kernel files (interval_kernels.cpp: values, interval_gradient_kernels.cpp:
// values with gradients): everything is in an unnamed namespace and inlined into each.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "eval/forward_mode.h"
#include "eval/interval_kernels.h"
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

}  // namespace isomesh
