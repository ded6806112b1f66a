// The one switch over a step's operation and operand form, shared by every evaluator that runs
// TapeProgram::steps (batch values, point values, interval kernels): each calls its visitor's
// member specialised at compile time to the operation, so a step costs one indirect jump.
#pragma once

#include <cassert>

#include "eval/batch_kernels.h"
#include "eval/tape_ops.h"

namespace isomesh {

constexpr int step_case(Op op, BatchForm form) {
    return static_cast<int>(op) * 3 + static_cast<int>(form);
}

/// Calls, for step s: v.constant() (Const), v.variable() (VarX, VarY, VarZ: copy register a),
/// v.template unary<op>(), or v.template binary<op, form>().
template <class Visitor>
[[gnu::always_inline]] inline void dispatch_step(const BatchStep& s, Visitor& v) {
    switch (step_case(s.op, s.form)) {
        case step_case(Op::Const, BatchForm::Registers):
            v.constant();
            break;
        case step_case(Op::VarX, BatchForm::Registers):
        case step_case(Op::VarY, BatchForm::Registers):
        case step_case(Op::VarZ, BatchForm::Registers):
            v.variable();
            break;
#define ISOMESH_UNARY_CASE(name)                    \
    case step_case(Op::name, BatchForm::Registers): \
        v.template unary<Op::name>();               \
        break;
            ISOMESH_UNARY_OPS(ISOMESH_UNARY_CASE)
#undef ISOMESH_UNARY_CASE
#define ISOMESH_BINARY_CASE(name)                             \
    case step_case(Op::name, BatchForm::Registers):           \
        v.template binary<Op::name, BatchForm::Registers>();  \
        break;                                                \
    case step_case(Op::name, BatchForm::ImmediateA):          \
        v.template binary<Op::name, BatchForm::ImmediateA>(); \
        break;                                                \
    case step_case(Op::name, BatchForm::ImmediateB):          \
        v.template binary<Op::name, BatchForm::ImmediateB>(); \
        break;
            ISOMESH_BINARY_OPS(ISOMESH_BINARY_CASE)
#undef ISOMESH_BINARY_CASE
        default:
            assert(!"no such step");
    }
}

}  // namespace isomesh
