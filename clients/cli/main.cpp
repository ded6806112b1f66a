// isomesh: the command-line face of the library. `isomesh COMMAND [ARGS...]`, one entry per
// command in kCommands; each command documents itself with `isomesh COMMAND --help`.
#include <cstdio>
#include <exception>
#include <span>
#include <string_view>
#include <vector>

#include "args.h"
#include "commands.h"

namespace {

using isomesh::cli::UsageError;

struct Command {
    std::string_view name;
    int (*run)(std::span<const std::string_view> args);
    std::string_view summary;
};

constexpr Command kCommands[] = {
    {"eval", isomesh::cli::run_eval, "evaluate a function at a point or on a box (JSON)"},
    {"mesh", isomesh::cli::run_mesh, "mesh a surface to a .glb, .stl, .ply or .obj file"},
};

int print_usage(std::FILE* to) {
    std::fputs("usage: isomesh COMMAND [ARGS...]\n\ncommands:\n", to);
    for (const Command& command : kCommands)
        std::fprintf(to, "  %-8.*s %.*s\n", static_cast<int>(command.name.size()),
                     command.name.data(), static_cast<int>(command.summary.size()),
                     command.summary.data());
    std::fputs("\n'isomesh COMMAND --help' describes a command.\n", to);
    return to == stdout ? 0 : 2;
}

const Command* find_command(std::string_view name) {
    for (const Command& command : kCommands) {
        if (command.name == name) return &command;
    }
    return nullptr;
}

int run(const Command& command, std::span<const std::string_view> args) {
    auto name = static_cast<int>(command.name.size());
    try {
        return command.run(args);
    } catch (const UsageError& error) {
        std::fprintf(stderr, "isomesh %.*s: %s\nrun 'isomesh %.*s --help' for usage\n", name,
                     command.name.data(), error.what(), name, command.name.data());
        return 2;
    } catch (const std::exception& error) {
        std::fprintf(stderr, "isomesh %.*s: internal error: %s\n", name, command.name.data(),
                     error.what());
        return 1;
    }
}

}  // namespace

int main(int argc, char** argv) {
    std::vector<std::string_view> args(argv + 1, argv + argc);
    if (args.empty()) return print_usage(stderr);
    if (args[0] == "--help" || args[0] == "-h" || args[0] == "help") return print_usage(stdout);
    const Command* command = find_command(args[0]);
    if (!command) {
        std::fprintf(stderr, "isomesh: unknown command '%.*s'\n\n",
                     static_cast<int>(args[0].size()), args[0].data());
        return print_usage(stderr);
    }
    return run(*command, std::span(args).subspan(1));
}
