// The language's built-in names and how each maps to tape instructions: functions, constants,
// and the power operator's special cases (e^x, real odd roots such as x^(1/3)).
#pragma once

#include <cstdint>
#include <span>
#include <string_view>

#include "tape/tape.h"

namespace isomesh::expr {

using Slot = std::uint32_t;

struct FunctionInfo {
    std::string_view name;
    int min_args;
    int max_args;  // -1: no upper bound
    Op op;         // the instruction for one-operation functions
    /// Emits the call; null for functions that are exactly `op` (unary, binary, or a left chain of
    /// `op` for variadic min/max). Precondition: min_args <= args.size() <= max_args.
    Slot (*emit)(TapeBuilder& builder, std::span<const Slot> args);
};

/// The function called `name`, or null. Names are case-sensitive (`sin`, not `Sin`).
const FunctionInfo* find_function(std::string_view name);

/// Emits the call of `function` on `args`. Precondition: the argument count is allowed.
Slot emit_call(TapeBuilder& builder, const FunctionInfo& function, std::span<const Slot> args);

/// The value of a named constant (`pi`, `π`, `e`), or false.
bool find_constant(std::string_view name, double& value);

/// True for names of non-finite numbers (`nan`, `inf`, `infinity` in any case, `∞`), which the
/// language refuses: a surface needs a finite function.
bool is_non_finite_name(std::string_view name);

/// base ^ exponent as GeoGebra reads it: e^x is exp(x); a whole constant exponent is PowInt
/// (exact sign for negative bases); a constant exponent p/q with q odd (such as 1/3 or 2/3) is the
/// real root, defined for negative bases as GeoGebra draws x^(1/3); anything else is std::pow.
Slot emit_power(TapeBuilder& builder, Slot base, Slot exponent);

}  // namespace isomesh::expr
