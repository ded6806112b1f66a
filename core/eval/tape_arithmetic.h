// The two number types the evaluators run tapes on, under one set of names: double (the scalar
// semantics of tape/op_math.h) and IntervalValue (eval/interval_math.h). Templates written against
// these names (the straight evaluation below, forward_mode.h) serve the point and the interval
// evaluators alike, so the two follow the same operations in the same order.
#pragma once

#include <cassert>
#include <span>
#include <vector>

#include "eval/interval_math.h"
#include "eval/tape_ops.h"
#include "tape/op_math.h"

namespace isomesh::arithmetic {

inline double unary(Op op, double a, double imm = 0.0) {
    return apply_unary(op, a, imm);
}
inline double binary(Op op, double a, double b) {
    return apply_binary(op, a, b);
}
inline IntervalValue unary(Op op, const IntervalValue& a, double imm = 0.0) {
    return interval_unary(op, a, imm);
}
inline IntervalValue binary(Op op, const IntervalValue& a, const IntervalValue& b) {
    return interval_binary(op, a, b);
}

template <class T>
T constant(double c);
template <>
inline double constant<double>(double c) {
    return c;
}
template <>
inline IntervalValue constant<IntervalValue>(double c) {
    return interval_constant(c);
}

/// The value of every instruction of `code`, in `slots` (resized as needed); `leaf(ins)` gives
/// the value of a leaf instruction (constants and variables; parameters are bound to constants).
template <class T, class Leaf>
std::span<const T> evaluate(std::span<const Instruction> code, std::vector<T>& slots,
                            const Leaf& leaf) {
    assert(!code.empty());
    if (slots.size() < code.size()) slots.resize(code.size());
    T* s = slots.data();
    for (std::size_t i = 0; i < code.size(); ++i) {
        const Instruction& ins = code[i];
        if (is_binary(ins.op))
            s[i] = binary(ins.op, s[ins.a], s[ins.b]);
        else if (is_unary(ins.op))
            s[i] = unary(ins.op, s[ins.a], ins.imm);
        else
            s[i] = leaf(ins);
    }
    return {s, code.size()};
}

}  // namespace isomesh::arithmetic
