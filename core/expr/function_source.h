// Where a function comes from, as the CLI (and later the server) receives it: the text of an
// expression, or `@path` naming a file.
#pragma once

#include <string_view>

#include "expr/compile.h"

namespace isomesh {

/// `@path.vm` compiles the Fidget model in that file (read_vm); any other `@path` is an error
/// naming the supported file types; anything else is an expression (compile_expression).
/// Reads files: a caller handling untrusted requests must not pass `@...` through.
CompileResult compile_source(std::string_view source_or_at_file, const CompileLimits& limits = {});

}  // namespace isomesh
