// Inline classification of tape operations for the evaluators' inner loops (op_arity() in
// tape.cpp is a table lookup behind a call). Relies on the order of enum Op: leaves, then unary,
// then binary operations.
#pragma once

#include "tape/tape.h"

namespace isomesh {

static_assert(Op::Param < Op::Neg && Op::Tanh < Op::Add && Op::Max == static_cast<Op>(kOpCount - 1),
              "enum Op must list leaves, then unary, then binary operations");

constexpr bool is_leaf(Op op) {
    return op <= Op::Param;
}
constexpr bool is_unary(Op op) {
    return op >= Op::Neg && op <= Op::Tanh;
}
constexpr bool is_binary(Op op) {
    return op >= Op::Add;
}

}  // namespace isomesh
