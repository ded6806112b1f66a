// The interval forward-mode kernel: a program's steps over W boxes, the enclosures of f and of its
// gradient in each (interval_kernels.h says how they stay exact; the lane formulas and the step
// loop are in interval_lanes.h).
#include "eval/interval_kernels.h"

#include "eval/interval_lanes.h"

namespace isomesh {

namespace {

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

}  // namespace

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
