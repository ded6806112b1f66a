// Scalar semantics of every tape operation, in one place: the point and batch evaluators and the
// constant folder all call these, so a folded constant is bit-identical to its evaluated value.
//
// Conventions (GeoGebra's, where it has one): ln/log of a negative number and sqrt of a negative
// number are NaN (undefined); division by zero gives +-inf; sgn(0) = 0; round() rounds half away
// from zero; cbrt is real for negative input.
#pragma once

#include <cmath>
#include <numbers>

#include "tape/tape.h"

namespace isomesh {

inline double sign_of(double v) { return v > 0.0 ? 1.0 : (v < 0.0 ? -1.0 : (v == v ? 0.0 : v)); }

/// x ^ n by repeated squaring (exact sign for odd n, 1 for n = 0 as std::pow).
inline double pow_int(double x, int n) {
    bool invert = n < 0;
    unsigned k = invert ? 0u - static_cast<unsigned>(n) : static_cast<unsigned>(n);
    double result = 1.0, base = x;
    while (k != 0) {
        if (k & 1u) result *= base;
        base *= base;
        k >>= 1u;
    }
    return invert ? 1.0 / result : result;
}

/// Value of unary `op` at `a`; `imm` is the instruction's immediate (PowInt's exponent).
inline double apply_unary(Op op, double a, double imm) {
    switch (op) {
        case Op::Neg: return -a;
        case Op::Square: return a * a;
        case Op::PowInt: return pow_int(a, static_cast<int>(imm));
        case Op::Sqrt: return std::sqrt(a);
        case Op::Cbrt: return std::cbrt(a);
        case Op::Abs: return std::fabs(a);
        case Op::Sgn: return sign_of(a);
        case Op::Floor: return std::floor(a);
        case Op::Ceil: return std::ceil(a);
        case Op::Round: return std::round(a);
        case Op::Exp: return std::exp(a);
        case Op::Ln: return std::log(a);
        case Op::Log10: return std::log10(a);
        case Op::Log2: return std::log2(a);
        case Op::Sin: return std::sin(a);
        case Op::Cos: return std::cos(a);
        case Op::Tan: return std::tan(a);
        case Op::Asin: return std::asin(a);
        case Op::Acos: return std::acos(a);
        case Op::Atan: return std::atan(a);
        case Op::Sinh: return std::sinh(a);
        case Op::Cosh: return std::cosh(a);
        case Op::Tanh: return std::tanh(a);
        default: return std::nan("");
    }
}

/// Where logsumexp(a, b) is max(a, b) exactly: |a - b| > kLogSumExpCutoff. The term dropped,
/// ln(1 + exp(-|a - b|)) < exp(-40) = 4.2e-18, is below the rounding error of the spelled-out
/// ln(exp(a) + exp(b)) (whose sum rounds away exp(-37) relative), and the cut lets interval
/// evaluation prove one operand irrelevant on a box, as for min and max (eval/tape_simplify.h).
inline constexpr double kLogSumExpCutoff = 40.0;

/// ln(exp(a) + exp(b)) without overflow: max(a, b) + ln(1 + exp(-|a - b|)), the second term
/// dropped beyond kLogSumExpCutoff. Symmetric in a and b bit for bit; NaN as a + b when either
/// operand is NaN; equal infinities give themselves.
inline double log_sum_exp(double a, double b) {
    if (a != a || b != b) return a + b;
    if (a == b) return a + std::numbers::ln2;
    const double hi = a > b ? a : b;
    const double d = hi - (a > b ? b : a);  // > 0, possibly +inf
    return d > kLogSumExpCutoff ? hi : hi + std::log1p(std::exp(-d));
}

/// sqrt(a^2 + b^2), spelled out (not std::hypot): the value of the sum of squares it replaces
/// within an ulp or two, the same overflow and underflow, and it vectorizes. Symmetric bit for
/// bit; NaN when either operand is NaN.
inline double euclidean_norm(double a, double b) {
    return std::sqrt(a * a + b * b);
}

/// Value of binary `op` at (a, b). Min and max propagate NaN (unlike std::fmin): an undefined
/// operand makes the result undefined, so no surface is invented where the function is undefined.
inline double apply_binary(Op op, double a, double b) {
    switch (op) {
        case Op::Add: return a + b;
        case Op::Sub: return a - b;
        case Op::Mul: return a * b;
        case Op::Div: return a / b;
        case Op::Pow: return std::pow(a, b);
        case Op::Atan2: return std::atan2(a, b);
        case Op::Min: return (a != a || b != b) ? a + b : (a < b ? a : b);
        case Op::Max: return (a != a || b != b) ? a + b : (a > b ? a : b);
        case Op::LogSumExp: return log_sum_exp(a, b);
        case Op::Hypot: return euclidean_norm(a, b);
        default: return std::nan("");
    }
}

}  // namespace isomesh
