// Sound interval extensions of every tape operation (the interval evaluator's arithmetic).
//
// Each function returns an IntervalValue whose interval contains every value the operation takes,
// as computed by the point evaluator (op_math.h, IEEE double with round-to-nearest and glibc's
// libm), for operands anywhere in the operand intervals where the operation is defined. The flags
// of the operands are propagated, and each operation adds its own: maybe_undefined where part of
// the operand lies outside its domain (sqrt, ln, asin, acos, 0/0, inf-inf, pow of a negative base),
// maybe_discontinuous where the operand reaches a pole or jump (1/0, tan at pi/2 + k pi, ln at 0,
// floor at an integer, atan2 across the negative x axis). An operand interval that is empty means
// the operand is undefined on the whole box; the result is then empty too, except where the
// operation yields a number from NaN (x^0 and 1^y, as std::pow).
//
// Precondition everywhere: an interval is either empty (Interval::empty()) or has lo <= hi, with
// endpoints possibly infinite; an infinite endpoint means the operand may take that infinity.
#pragma once

#include <algorithm>

#include "eval/interval.h"
#include "tape/tape.h"

namespace isomesh {

/// The smallest interval containing a and b (either may be empty).
inline Interval hull(const Interval& a, const Interval& b) {
    if (a.is_empty()) return b;
    if (b.is_empty()) return a;
    return {std::min(a.lo, b.lo), std::max(a.hi, b.hi)};
}

/// [value, value]; empty (and undefined) for NaN.
IntervalValue interval_constant(double value);

/// Enclosure of unary `op` over `a`; `imm` is the instruction's immediate (PowInt's exponent).
/// Preconditions: op_arity(op) == 1; for PowInt, imm is a whole number within the range of int.
IntervalValue interval_unary(Op op, const IntervalValue& a, double imm);

/// Enclosure of binary `op` over a x b. Precondition: op_arity(op) == 2.
IntervalValue interval_binary(Op op, const IntervalValue& a, const IntervalValue& b);

}  // namespace isomesh
