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
static_assert(kIntervalLanes % kChunk == 0);

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
    return (d.lo == D{}) & (d.hi == D{});
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

/// Binary `op` over all lanes, as unary_value. A division by an interval holding 0 is left to the
/// reference (`bad` is set).
template <std::size_t W, Op op, class D, class M>
ISOMESH_KERNEL Value<D, M> binary_value(const Ends<D>& a, const M& fa, const Ends<D>& b,
                                        const M& fb, M& bad) {
    const M flags = fa | fb;
    if constexpr (op == Op::Add) {
        return {add(a, b), flags};
    } else if constexpr (op == Op::Sub) {
        return {{a.lo - b.hi, a.hi - b.lo}, flags};  // x + (-y) is x - y, bit for bit
    } else if constexpr (op == Op::Mul) {
        return {mul(a, b), flags};
    } else if constexpr (op == Op::Div) {
        bad |= as_mask<M>((b.lo <= D{}) & (b.hi >= D{}));
        return {div(a, b), flags};
    } else if constexpr (op == Op::Min) {
        return {{fold_min(a.lo, b.lo), fold_min(a.hi, b.hi)}, flags};
    } else if constexpr (op == Op::Max) {
        return {{fold_max(a.lo, b.lo), fold_max(a.hi, b.hi)}, flags};
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

/// V lanes of the register file, from lane `offset` on, and which of them go to the reference.
template <std::size_t V, class Register>
struct Lanes {
    using D = typename LaneTypes<V>::D;
    using M = typename LaneTypes<V>::M;
    Register* registers;
    std::size_t offset;
    M bad;

    ISOMESH_MEMBER Ends<D> ends(std::uint32_t r) const {
        return {load<D>(registers[r].lo + offset), load<D>(registers[r].hi + offset)};
    }
    ISOMESH_MEMBER M flags(std::uint32_t r) const { return load<M>(registers[r].flags + offset); }
    ISOMESH_MEMBER void store_value(std::uint32_t r, const Value<D, M>& v) {
        store(registers[r].lo + offset, v.ends.lo);
        store(registers[r].hi + offset, v.ends.hi);
        store(registers[r].flags + offset, v.flags);
        bad |= as_mask<M>(nonfinite(v.ends));
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
};

/// A Const step's value: interval_constant(c) in every lane.
template <std::size_t W>
ISOMESH_KERNEL auto constant_value(double c) {
    LaneResults<W> r;
    for (std::size_t l = 0; l < W; ++l) r.set(l, interval_constant(c));
    return r.template value<typename LaneTypes<W>::D, typename LaneTypes<W>::M>();
}

/// One step of the interval evaluator over V lanes of the register file (see Chunked).
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
        lanes.store_value(s.out, unary_value<V, op>(lanes.ends(s.a), lanes.flags(s.a), s.imm));
    }

    template <Op op, BatchForm form>
    ISOMESH_MEMBER void binary() {
        constexpr bool a_in_register = form != BatchForm::ImmediateA;
        constexpr bool b_in_register = form != BatchForm::ImmediateB;
        const Ends<D> a = lanes.template operand<a_in_register>(s.a, s.imm);
        const Ends<D> b = lanes.template operand<b_in_register>(s.b, s.imm);
        const M fa = lanes.template operand_flags<a_in_register>(s.a);
        const M fb = lanes.template operand_flags<b_in_register>(s.b);
        lanes.store_value(s.out, binary_value<V, op>(a, fa, b, fb, lanes.bad));
        if constexpr (op == Op::Min || op == Op::Max)
            record_choice<V, op>(a, fa, b, fb, choice, choice_stride);
    }
};

/// One step of the interval forward-mode evaluator over V lanes of the register file: the value
/// as IntervalStep computes it, then each gradient component from the partial derivatives of
/// forward_mode.h.
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

    ISOMESH_MEMBER void store_gradient(int k, const Ends<D>& g) {
        store(lanes.registers[s.out].grad_lo[k] + lanes.offset, g.lo);
        store(lanes.registers[s.out].grad_hi[k] + lanes.offset, g.hi);
        lanes.bad |= as_mask<M>(nonfinite(g));
    }

    ISOMESH_MEMBER void check(const Ends<D>& partial) {
        lanes.bad |= as_mask<M>(nonfinite(partial));
    }

    ISOMESH_MEMBER void constant() {
        lanes.store_value(s.out, constant_value<V>(s.imm));
        for (int k = 0; k < 3; ++k) store_gradient(k, {D{}, D{}});
    }
    ISOMESH_MEMBER void variable() {
        lanes.store_value(s.out, {lanes.ends(s.a), lanes.flags(s.a)});
        for (int k = 0; k < 3; ++k) store_gradient(k, gradient<true>(s.a, k));
    }

    template <Op op>
    ISOMESH_MEMBER void unary() {
        const Ends<D> a = lanes.ends(s.a);
        const M fa = lanes.flags(s.a);
        const Value<D, M> r = unary_value<V, op>(a, fa, s.imm);
        lanes.store_value(s.out, r);
        const Ends<D> partial = unary_partial<op>(a, fa, r);
        check(partial);
        for (int k = 0; k < 3; ++k) {
            const Ends<D> d = gradient<true>(s.a, k);
            store_gradient(k, op == Op::Neg ? term_minus_one(d) : term(partial, d));
        }
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
            // r holding 0 gives an infinite partial: the lane goes to the reference.
            return div({L::splat(0.5), L::splat(0.5)}, r.ends);
        } else if (op == Op::PowInt && s.imm > 0.0) {
            // imm * a^(imm - 1), a^0 being [1, 1] as the reference's unary() makes it.
            const auto n = static_cast<unsigned>(s.imm);
            const D one = L::splat(1.0);
            const Ends<D> power = n == 1 ? Ends<D>{one, one} : pow_int_ends(a, n - 1, one);
            return mul({L::splat(s.imm), L::splat(s.imm)}, power);
        } else if constexpr (op == Op::Exp) {
            return r.ends;
        } else if constexpr (op == Op::Ln) {
            return div({L::splat(1.0), L::splat(1.0)}, a);  // a holding 0: an infinite value
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
        const Ends<D> a = lanes.template operand<a_in_register>(s.a, s.imm);
        const Ends<D> b = lanes.template operand<b_in_register>(s.b, s.imm);
        const M fa = lanes.template operand_flags<a_in_register>(s.a);
        const M fb = lanes.template operand_flags<b_in_register>(s.b);
        const Value<D, M> r = binary_value<V, op>(a, fa, b, fb, lanes.bad);
        lanes.store_value(s.out, r);
        if constexpr (op == Op::Min || op == Op::Max) {
            record_choice<V, op>(a, fa, b, fb, choice, choice_stride);
            const auto pick_a = a_wins<op>(a, b);
            const auto pick_b = a_wins<op>(b, a);
            for (int k = 0; k < 3; ++k) {
                const Ends<D> ga = gradient<a_in_register>(s.a, k);
                const Ends<D> gb = gradient<b_in_register>(s.b, k);
                // forward_mode::either: the hull of two finite (so non-empty) intervals.
                const Ends<D> either{fold_min(ga.lo, gb.lo), fold_max(ga.hi, gb.hi)};
                store_gradient(k, {pick_a   ? ga.lo
                                   : pick_b ? gb.lo
                                            : either.lo,
                                   pick_a   ? ga.hi
                                   : pick_b ? gb.hi
                                            : either.hi});
            }
            return;
        }
        if constexpr (op == Op::Add || op == Op::Sub) {
            for (int k = 0; k < 3; ++k) {
                const Ends<D> gb = gradient<b_in_register>(s.b, k);
                store_gradient(k, add(term_one(gradient<a_in_register>(s.a, k)),
                                      op == Op::Add ? term_one(gb) : term_minus_one(gb)));
            }
            return;
        }
        Ends<D> da{}, db{};  // the partial derivatives
        if constexpr (op == Op::Mul) {
            da = b;
            db = a;
        } else if constexpr (op == Op::Div) {
            da = div({L::splat(1.0), L::splat(1.0)}, b);
            const Ends<D> q = div(r.ends, b);
            db = {-q.hi, -q.lo};
        } else {
            LaneResults<V> pa, pb;
            for (std::size_t l = 0; l < V; ++l) {
                const auto p = forward_mode::binary_partials(
                    op, lane_value(a, fa, l), lane_value(b, fb, l), lane_value(r.ends, r.flags, l));
                pa.set(l, p.da);
                pb.set(l, p.db);
            }
            da = pa.template ends<D>();
            db = pb.template ends<D>();
        }
        check(da);
        check(db);
        for (int k = 0; k < 3; ++k) {
            store_gradient(k, add(term(da, gradient<a_in_register>(s.a, k)),
                                  term(db, gradient<b_in_register>(s.b, k))));
        }
    }
};

template <std::size_t W, template <std::size_t, class> class Step, class Register>
ISOMESH_KERNEL std::uint32_t run(std::span<const BatchStep> steps, Register* registers,
                                 Choice* choices, std::size_t choice_count) {
    constexpr std::size_t V = W == 1 ? 1 : kChunk;
    constexpr std::size_t kChunks = W / V;
    Lanes<V, Register> chunks[kChunks];
    for (std::size_t c = 0; c < kChunks; ++c) {
        chunks[c].registers = registers;
        chunks[c].offset = c * V;
        chunks[c].bad = typename LaneTypes<V>::M{};
        for (std::uint32_t r = 0; r < 3; ++r)  // the box must be finite too
            chunks[c].bad |= as_mask<typename LaneTypes<V>::M>(nonfinite(chunks[c].ends(r)));
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
        if (s.op == Op::Min || s.op == Op::Max) ++choice;
    }
    std::uint32_t mask = 0;
    for (std::size_t c = 0; c < kChunks; ++c)
        for (std::size_t l = 0; l < V; ++l)
            mask |= static_cast<std::uint32_t>(lane(chunks[c].bad, l) != 0) << (c * V + l);
    return mask;
}

}  // namespace

std::uint32_t run_interval_steps(std::span<const BatchStep> steps, IntervalRegister<1>* registers,
                                 Choice* choices, std::size_t choice_count) {
    return run<1, IntervalStep>(steps, registers, choices, choice_count);
}

ISOMESH_VECTOR_CLONES std::uint32_t run_interval_steps(std::span<const BatchStep> steps,
                                                       IntervalRegister<kIntervalLanes>* registers,
                                                       Choice* choices, std::size_t choice_count) {
    return run<kIntervalLanes, IntervalStep>(steps, registers, choices, choice_count);
}

std::uint32_t run_gradient_steps(std::span<const BatchStep> steps, GradientRegister<1>* registers,
                                 Choice* choices, std::size_t choice_count) {
    return run<1, GradientStep>(steps, registers, choices, choice_count);
}

ISOMESH_VECTOR_CLONES std::uint32_t run_gradient_steps(std::span<const BatchStep> steps,
                                                       GradientRegister<kIntervalLanes>* registers,
                                                       Choice* choices, std::size_t choice_count) {
    return run<kIntervalLanes, GradientStep>(steps, registers, choices, choice_count);
}

}  // namespace isomesh
