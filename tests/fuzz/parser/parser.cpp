// libFuzzer target for the function language and the .vm reader: any bytes must compile to a valid
// tape or give an error, never crash, leak or hit undefined behaviour (built with ASan and UBSan).
// Beyond not crashing it checks the contracts: a valid tape within the limits, or a non-empty,
// valid UTF-8 message and no tape.
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "../../expr/tape_interpreter.h"
#include "expr/compile.h"
#include "expr/utf8.h"
#include "expr/vm_reader.h"

namespace {

void require(bool condition) {
    if (!condition) __builtin_trap();
}

bool is_valid_utf8(std::string_view text) {
    for (std::size_t pos = 0; pos < text.size();) {
        std::size_t length = isomesh::expr::decode_utf8(text, pos).length;
        if (length == 0) return false;
        pos += length;
    }
    return true;
}

void check(const isomesh::CompileResult& result, const isomesh::CompileLimits& limits) {
    if (result.ok()) {
        require(result.tape.validate().empty());
        require(result.tape.size() <= limits.max_instructions);
        // Run the tape once, so operations on odd values (PowInt exponents, parameter indices)
        // are exercised under the sanitizers.
        std::vector<double> params(result.tape.params.size(), 0.5);
        (void)isomesh::testing::interpret(result.tape, 0.5, -0.25, 2.0, params);
    } else {
        require(!result.error->message.empty() && result.tape.code.empty());
        require(is_valid_utf8(result.error->to_string()));
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    std::string_view text(reinterpret_cast<const char*>(data), size);
    isomesh::CompileLimits limits;
    limits.max_instructions = 5000;  // small enough for the limit itself to be reached
    limits.max_depth = 64;
    check(isomesh::compile_expression(text, limits), limits);
    check(isomesh::read_vm(text, limits), limits);
    return 0;
}
