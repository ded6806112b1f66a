// A deliberately tiny reference interpreter of tapes, for checking what the compiler emits
// independently of the evaluators in core/eval. Scalar semantics come from tape/op_math.h.
#pragma once

#include <cmath>
#include <span>
#include <vector>

#include "tape/op_math.h"
#include "tape/tape.h"

namespace isomesh::testing {

inline double interpret(const Tape& tape, double x, double y, double z,
                        std::span<const double> params = {}) {
    std::vector<double> slots(tape.size());
    for (std::size_t n = 0; n < tape.size(); ++n) {
        const Instruction& i = tape.code[n];
        switch (i.op) {
            case Op::Const:
                slots[n] = i.imm;
                break;
            case Op::VarX:
                slots[n] = x;
                break;
            case Op::VarY:
                slots[n] = y;
                break;
            case Op::VarZ:
                slots[n] = z;
                break;
            case Op::Param:
                slots[n] = params[static_cast<std::size_t>(i.imm)];
                break;
            default:
                slots[n] = op_arity(i.op) == 1 ? apply_unary(i.op, slots[i.a], i.imm)
                                               : apply_binary(i.op, slots[i.a], slots[i.b]);
        }
    }
    return slots.back();
}

inline int count_ops(const Tape& tape, Op op) {
    int count = 0;
    for (const Instruction& i : tape.code) count += i.op == op;
    return count;
}

}  // namespace isomesh::testing
