// What the CLI prints: one JSON object per line on stdout for results, "isomesh: ..." messages on
// stderr for errors and warnings.
#pragma once

#include <string_view>

#include <nlohmann/json.hpp>

namespace isomesh::cli {

void print_error(std::string_view message);
void print_warning(std::string_view message);
/// One compact line. Keys keep their insertion order; NaN and infinities print as null.
void print_json_line(const nlohmann::ordered_json& value);

}  // namespace isomesh::cli
