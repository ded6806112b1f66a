#include "function_input.h"

#include <string>

#include "args.h"
#include "eval/tape_field.h"
#include "expr/function_source.h"
#include "expr/parameters.h"
#include "output.h"

namespace isomesh::cli {

namespace {

/// The error (after the file name for an error inside a model file), then for a one-line
/// expression the expression and a caret under the column.
void print_compile_error(std::string_view source, const CompileError& error) {
    bool from_file = source.starts_with('@');
    if (from_file && error.multiline) {
        print_error(std::string(source.substr(1)) + ": " + error.to_string());
        return;
    }
    print_error(error.to_string());
    if (from_file || error.multiline || error.column <= 0) return;
    std::string caret(static_cast<std::size_t>(error.column - 1), ' ');
    std::fprintf(stderr, "  %.*s\n  %s^\n", static_cast<int>(source.size()), source.data(),
                 caret.c_str());
}

}  // namespace

std::optional<FunctionInput> load_function(std::string_view source,
                                           std::span<const std::string_view> param_items) {
    auto values = parse_assignments(param_items, "--param");
    CompileResult compiled = compile_source(source);
    if (!compiled.ok()) {
        print_compile_error(source, *compiled.error);
        return std::nullopt;
    }
    ParameterBinding binding = bind_parameters(compiled.tape, values);
    if (binding.warning) print_warning(*binding.warning);
    if (!binding.ok()) {
        print_error(*binding.error + " (give each with --param NAME=VALUE)");
        return std::nullopt;
    }
    FunctionInput input;
    input.tape = std::make_shared<const Tape>(std::move(compiled.tape));
    input.params = binding.values;
    input.field = make_tape_field(input.tape, std::move(binding.values));
    return input;
}

}  // namespace isomesh::cli
