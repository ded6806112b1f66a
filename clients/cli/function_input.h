// The function a command works on, from its EXPR argument (an expression or `@model.vm`) and its
// `--param NAME=VALUE` options: compiled, parameters bound, ready to evaluate.
#pragma once

#include <memory>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "eval/evaluator.h"
#include "tape/tape.h"

namespace isomesh::cli {

struct FunctionInput {
    std::shared_ptr<const Tape> tape;
    std::vector<double> params;  // values of tape->params, in order
    std::shared_ptr<const Field> field;
};

/// Compiles `source` and binds `param_items` (`name=value`, see parse_assignments). Prints
/// compile errors (with the expression and a caret under the column), missing parameters and
/// unused-parameter warnings on stderr; returns nothing on error. Throws UsageError for a
/// malformed `name=value`.
std::optional<FunctionInput> load_function(std::string_view source,
                                           std::span<const std::string_view> param_items);

}  // namespace isomesh::cli
