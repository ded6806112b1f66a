#include "expr/functions.h"

#include <array>
#include <cassert>
#include <cmath>
#include <numbers>

namespace isomesh::expr {

namespace {

/// log(b, x): the logarithm of x in base b, as GeoGebra's two-argument log.
Slot emit_log(TapeBuilder& builder, std::span<const Slot> args) {
    if (args.size() == 1) return builder.unary(Op::Ln, args[0]);
    return builder.binary(Op::Div, builder.unary(Op::Ln, args[1]), builder.unary(Op::Ln, args[0]));
}

constexpr std::array kFunctions = {
    FunctionInfo{"sin", 1, 1, Op::Sin, nullptr},
    FunctionInfo{"cos", 1, 1, Op::Cos, nullptr},
    FunctionInfo{"tan", 1, 1, Op::Tan, nullptr},
    FunctionInfo{"asin", 1, 1, Op::Asin, nullptr},
    FunctionInfo{"arcsin", 1, 1, Op::Asin, nullptr},
    FunctionInfo{"acos", 1, 1, Op::Acos, nullptr},
    FunctionInfo{"arccos", 1, 1, Op::Acos, nullptr},
    FunctionInfo{"atan", 1, 1, Op::Atan, nullptr},
    FunctionInfo{"arctan", 1, 1, Op::Atan, nullptr},
    FunctionInfo{"atan2", 2, 2, Op::Atan2, nullptr},
    FunctionInfo{"sinh", 1, 1, Op::Sinh, nullptr},
    FunctionInfo{"cosh", 1, 1, Op::Cosh, nullptr},
    FunctionInfo{"tanh", 1, 1, Op::Tanh, nullptr},
    FunctionInfo{"exp", 1, 1, Op::Exp, nullptr},
    FunctionInfo{"ln", 1, 1, Op::Ln, nullptr},
    FunctionInfo{"log", 1, 2, Op::Ln, emit_log},
    FunctionInfo{"lg", 1, 1, Op::Log10, nullptr},
    FunctionInfo{"log10", 1, 1, Op::Log10, nullptr},
    FunctionInfo{"ld", 1, 1, Op::Log2, nullptr},
    FunctionInfo{"log2", 1, 1, Op::Log2, nullptr},
    FunctionInfo{"sqrt", 1, 1, Op::Sqrt, nullptr},
    FunctionInfo{"cbrt", 1, 1, Op::Cbrt, nullptr},
    FunctionInfo{"abs", 1, 1, Op::Abs, nullptr},
    FunctionInfo{"sgn", 1, 1, Op::Sgn, nullptr},
    FunctionInfo{"sign", 1, 1, Op::Sgn, nullptr},
    FunctionInfo{"floor", 1, 1, Op::Floor, nullptr},
    FunctionInfo{"ceil", 1, 1, Op::Ceil, nullptr},
    FunctionInfo{"round", 1, 1, Op::Round, nullptr},
    FunctionInfo{"min", 2, -1, Op::Min, nullptr},
    FunctionInfo{"max", 2, -1, Op::Max, nullptr},
};

/// The odd denominator q <= 99 of a constant exponent c = p/q, |c| <= 64, that is not whole
/// (exactly: the double p/q equals c), or 0.
int odd_denominator(double c, int& numerator) {
    if (!std::isfinite(c) || c == std::trunc(c) || std::abs(c) > 64) return 0;
    for (int q = 3; q <= 99; q += 2) {
        double p = std::round(c * q);
        if (p / q == c) {
            numerator = static_cast<int>(p);
            return q;
        }
    }
    return 0;
}

/// The real q-th root of base^p for odd q: cube roots through cbrt (exact and continuous), other
/// roots as sgn(base)^p * |base|^(p/q).
Slot emit_odd_root_power(TapeBuilder& builder, Slot base, int p, int q, Slot exponent) {
    if (q == 3) return builder.pow_int(builder.unary(Op::Cbrt, base), p);
    Slot magnitude = builder.binary(Op::Pow, builder.unary(Op::Abs, base), exponent);
    if (p % 2 == 0) return magnitude;
    return builder.binary(Op::Mul, builder.unary(Op::Sgn, base), magnitude);
}

}  // namespace

const FunctionInfo* find_function(std::string_view name) {
    for (const FunctionInfo& f : kFunctions) {
        if (f.name == name) return &f;
    }
    return nullptr;
}

Slot emit_call(TapeBuilder& builder, const FunctionInfo& function, std::span<const Slot> args) {
    assert(static_cast<int>(args.size()) >= function.min_args);
    assert(function.max_args < 0 || static_cast<int>(args.size()) <= function.max_args);
    if (function.emit) return function.emit(builder, args);
    if (op_arity(function.op) == 1) return builder.unary(function.op, args[0]);
    Slot result = args[0];
    for (std::size_t i = 1; i < args.size(); ++i)
        result = builder.binary(function.op, result, args[i]);
    return result;
}

bool find_constant(std::string_view name, double& value) {
    if (name == "pi" || name == "\u03C0") {
        value = std::numbers::pi;
        return true;
    }
    if (name == "e") {
        value = std::numbers::e;
        return true;
    }
    return false;
}

bool is_non_finite_name(std::string_view name) {
    if (name == "\u221E") return true;
    auto lower = [](char c) {
        return (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c;
    };
    for (std::string_view word :
         {std::string_view("nan"), std::string_view("inf"), std::string_view("infinity")}) {
        bool equal = word.size() == name.size();
        for (std::size_t i = 0; equal && i < word.size(); ++i) equal = lower(name[i]) == word[i];
        if (equal) return true;
    }
    return false;
}

Slot emit_power(TapeBuilder& builder, Slot base, Slot exponent) {
    if (builder.is_constant(base) && builder.constant_value(base) == std::numbers::e)
        return builder.unary(Op::Exp, exponent);
    if (builder.is_constant(exponent)) {
        int p = 0;
        int q = odd_denominator(builder.constant_value(exponent), p);
        if (q != 0) return emit_odd_root_power(builder, base, p, q, exponent);
    }
    return builder.binary(Op::Pow, base, exponent);
}

}  // namespace isomesh::expr
