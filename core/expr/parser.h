// Parser of the function language (grammar in expr/compile.h): Pratt parsing, that is top-down
// operator precedence (V. Pratt, "Top down operator precedence", POPL 1973), emitting tape
// instructions straight into a TapeBuilder as each construct is recognised. There is no syntax
// tree: the builder's hash-consing already shares repeated subexpressions and folds constants.
//
// Binding powers, loosest first:
//   10  + -                          binary, left-associative
//   20  * / and juxtaposition        binary, left-associative (implicit multiplication)
//   30  prefix - +                   operand binds ^ but not *: -x^2 = -(x^2), -2x = (-2)x
//   40  ^ and superscripts           right-associative; the exponent may start with a sign
#pragma once

#include <string_view>

#include "expr/compile.h"
#include "expr/functions.h"

namespace isomesh::expr {

/// Parses `source` and emits it into `builder`. On success sets `output` to the slot of
/// lhs - rhs (or of the bare expression) and returns no error.
std::optional<CompileError> parse_equation(std::string_view source, const CompileLimits& limits,
                                           TapeBuilder& builder, Slot& output);

}  // namespace isomesh::expr
