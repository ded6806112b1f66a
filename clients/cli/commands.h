// The isomesh subcommands. Each takes the arguments after its name and returns the exit status:
// 0 on success, 1 when the work failed (the reason printed on stderr). A mistake in the command
// line throws UsageError (args.h), which main() reports with exit status 2. To add a command,
// declare it here and add one line to kCommands in main.cpp.
#pragma once

#include <span>
#include <string_view>

namespace isomesh::cli {

/// `isomesh eval EXPR (--at x,y,z | --box x0,x1,y0,y1,z0,z1) [--param NAME=VALUE]...`
int run_eval(std::span<const std::string_view> args);

/// `isomesh mesh EXPR -o FILE [--param NAME=VALUE]... [--box ...] [--depth MIN,MAX]
/// [--threads N] [--stats]`
int run_mesh(std::span<const std::string_view> args);

}  // namespace isomesh::cli
