#include "expr/function_source.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <string>

#include "expr/utf8.h"
#include "expr/vm_reader.h"

namespace isomesh {

namespace {

CompileResult failure(std::string message) {
    CompileResult result;
    result.error = CompileError{std::move(message), 1, 0, false};
    return result;
}

/// Reads at most max_bytes + 1 bytes of the file (enough to tell that it is too large).
bool read_file(const std::string& path, std::size_t max_bytes, std::string& text) {
    std::ifstream file(path, std::ios::binary | std::ios::ate);
    std::streamoff size = file ? static_cast<std::streamoff>(file.tellg()) : -1;
    if (size < 0) return false;
    text.resize(std::min(static_cast<std::size_t>(size), max_bytes + 1));
    file.seekg(0);
    file.read(text.data(), static_cast<std::streamsize>(text.size()));
    return !file.fail();
}

}  // namespace

CompileResult compile_source(std::string_view source, const CompileLimits& limits) {
    if (!source.starts_with('@')) return compile_expression(source, limits);
    std::string path(source.substr(1));
    if (!path.ends_with(".vm"))
        return failure("unsupported file " + expr::quote(path, 200) + ": expected a .vm model");
    std::string text;
    if (!read_file(path, limits.max_vm_bytes, text))
        return failure("cannot read " + expr::quote(path, 200) + ": " + std::strerror(errno));
    return read_vm(text, limits);
}

}  // namespace isomesh
