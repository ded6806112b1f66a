// Inline classification of tape operations for the evaluators' inner loops (op_arity() in
// tape.cpp is a table lookup behind a call). Relies on the order of enum Op: leaves, then unary,
// then binary operations.
#pragma once

#include "tape/tape.h"

namespace isomesh {

static_assert(Op::Param < Op::Neg && Op::Tanh < Op::Add &&
                  Op::Hypot == static_cast<Op>(kOpCount - 1),
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
/// The operations that return one operand unchanged wherever interval evaluation proves it wins
/// (min, max, and logsumexp beyond kLogSumExpCutoff): tape simplification drops the other.
constexpr bool is_choice(Op op) {
    return op == Op::Min || op == Op::Max || op == Op::LogSumExp;
}

// Every unary and binary operation, for the evaluators' switches over operations: X(name) per
// operation.
#define ISOMESH_UNARY_OPS(X)                                                                \
    X(Neg)                                                                                  \
    X(Square)                                                                               \
    X(PowInt) X(Sqrt) X(Cbrt) X(Abs) X(Sgn) X(Floor) X(Ceil) X(Round) X(Exp) X(Ln) X(Log10) \
        X(Log2) X(Sin) X(Cos) X(Tan) X(Asin) X(Acos) X(Atan) X(Sinh) X(Cosh) X(Tanh)
#define ISOMESH_BINARY_OPS(X) X(Add) X(Sub) X(Mul) X(Div) X(Pow) X(Atan2) X(Min) X(Max) X(LogSumExp) \
    X(Hypot)
#define ISOMESH_COUNT(name) +1
static_assert(5 ISOMESH_UNARY_OPS(ISOMESH_COUNT) ISOMESH_BINARY_OPS(ISOMESH_COUNT) == kOpCount,
              "the lists must name every operation");
#undef ISOMESH_COUNT

}  // namespace isomesh
