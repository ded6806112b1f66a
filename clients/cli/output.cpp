#include "output.h"

#include <cstdio>
#include <string>

namespace isomesh::cli {

void print_error(std::string_view message) {
    std::fprintf(stderr, "isomesh: %.*s\n", static_cast<int>(message.size()), message.data());
}

void print_warning(std::string_view message) {
    std::fprintf(stderr, "isomesh: warning: %.*s\n", static_cast<int>(message.size()),
                 message.data());
}

void print_json_line(const nlohmann::ordered_json& value) {
    // Replace rather than throw on invalid UTF-8 in strings (names come from user input).
    std::string line = value.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    std::printf("%s\n", line.c_str());
    std::fflush(stdout);
}

}  // namespace isomesh::cli
