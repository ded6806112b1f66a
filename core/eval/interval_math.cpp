// Interval arithmetic for the tape operations: Moore, "Interval Analysis" (1966) for the arithmetic
// operations; Snyder, "Interval analysis for computer graphics" (SIGGRAPH 1992) and Duff, "Interval
// arithmetic and recursive subdivision for implicit functions and constructive solid geometry"
// (SIGGRAPH 1992) for the elementary functions, poles, and the CSG operations min and max.
//
// Rounding. The point evaluator computes every operation in IEEE double with round-to-nearest. For
// the correctly rounded operations (+ - * / sqrt, and products of them such as pow_int) rounding is
// monotone, so a monotone operation evaluated at the operand endpoints bounds the computed value at
// every interior point: no widening is needed to contain what the point evaluator computes. libm
// functions are not correctly rounded (glibc documents errors of up to 4 ulps on x86-64), so their
// endpoint values are widened outward by kLibmSlack, relative, which is more than twice the worst
// error. A libm result that is exactly zero is kept as it is for the sign-correct functions (they
// return 0 only at their exact zero, with the right sign around it), so that sqrt(sin(x)) on [0, 1]
// is not reported undefined; exp and pow reach 0 by underflow instead and get an absolute slack.
#include "eval/interval_math.h"

#include "eval/interval_ranges.h"

namespace isomesh {

IntervalValue interval_constant(double value) {
    if (std::isnan(value)) return {Interval::empty(), false, true};
    return {{value, value}, false, false};
}

IntervalValue interval_unary(Op op, const IntervalValue& a, double imm) {
    return interval_ranges::unary(op, a, imm);
}

IntervalValue interval_binary(Op op, const IntervalValue& a, const IntervalValue& b) {
    return interval_ranges::binary(op, a, b);
}

}  // namespace isomesh
