#include "eval/reference_evaluation.h"

#include <cmath>

#include "eval/tape_arithmetic.h"

namespace isomesh {

namespace {

double leaf_value(const Instruction& ins, const glm::dvec3& p) {
    switch (ins.op) {
        case Op::VarX:
            return p.x;
        case Op::VarY:
            return p.y;
        case Op::VarZ:
            return p.z;
        default:
            return ins.imm;  // Const (parameters are bound to constants)
    }
}

IntervalValue leaf_interval(const Instruction& ins, const Box& box) {
    switch (ins.op) {
        case Op::VarX:
            return {{box.lo.x, box.hi.x}, false, false};
        case Op::VarY:
            return {{box.lo.y, box.hi.y}, false, false};
        case Op::VarZ:
            return {{box.lo.z, box.hi.z}, false, false};
        default:
            return interval_constant(ins.imm);
    }
}

/// The choices proven at the program's min and max instructions, from their operands' enclosures.
template <class Value>
void record_choices(const TapeProgram& program, std::span<const Value> slots,
                    std::span<Choice> choices, const IntervalValue& (*value_of)(const Value&)) {
    for (std::size_t c = 0; c < program.choice_slots.size(); ++c) {
        const Instruction& ins = program.code[program.choice_slots[c]];
        choices[c] = prove_choice(ins.op, value_of(slots[ins.a]), value_of(slots[ins.b]));
    }
}

const IntervalValue& itself(const IntervalValue& v) {
    return v;
}
const IntervalValue& tangent_value(const forward_mode::Tangent<IntervalValue>& t) {
    return t.value;
}

}  // namespace

double ReferenceEvaluation::value(const TapeProgram& program, const glm::dvec3& p) {
    auto leaf = [&p](const Instruction& ins) { return leaf_value(ins, p); };
    return arithmetic::evaluate(std::span(program.code), slots_, leaf).back();
}

ValueGradient ReferenceEvaluation::value_gradient(const TapeProgram& program, const glm::dvec3& p) {
    auto leaf = [&p](const Instruction& ins) { return leaf_value(ins, p); };
    forward_mode::Tangent<double> t = forward_mode::differentiate(program.code, duals_, leaf);
    if (std::isnan(t.value)) return {t.value, glm::dvec3(t.value)};  // no gradient where undefined
    return {t.value, {t.grad[0], t.grad[1], t.grad[2]}};
}

IntervalValue ReferenceEvaluation::interval(const TapeProgram& program, const Box& box,
                                            std::span<Choice> choices) {
    auto leaf = [&box](const Instruction& ins) { return leaf_interval(ins, box); };
    std::span<const IntervalValue> slots =
        arithmetic::evaluate(std::span(program.code), intervals_, leaf);
    record_choices(program, slots, choices, itself);
    return slots.back();
}

IntervalGradient ReferenceEvaluation::interval_gradient(const TapeProgram& program, const Box& box,
                                                        std::span<Choice> choices) {
    auto leaf = [&box](const Instruction& ins) { return leaf_interval(ins, box); };
    forward_mode::Tangent<IntervalValue> t =
        forward_mode::differentiate(program.code, interval_duals_, leaf);
    record_choices(program,
                   std::span<const forward_mode::Tangent<IntervalValue>>(interval_duals_.data(),
                                                                         program.code.size()),
                   choices, tangent_value);
    return {t.value, {t.grad[0].value, t.grad[1].value, t.grad[2].value}};
}

}  // namespace isomesh
