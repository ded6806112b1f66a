// The interval kernel: a program's steps over W boxes, the enclosure of f in each
// (interval_kernels.h says how they stay exact; the lane formulas and the step loop are in
// interval_lanes.h).
#include "eval/interval_kernels.h"

#include "eval/interval_lanes.h"

namespace isomesh {

namespace {

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

}  // namespace isomesh
