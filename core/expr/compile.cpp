#include "expr/compile.h"

#include "expr/parser.h"

namespace isomesh {

std::string CompileError::to_string() const {
    if (column <= 0) return multiline ? message + " at line " + std::to_string(line) : message;
    std::string where = multiline ? "line " + std::to_string(line) + ", column " : "column ";
    return message + " at " + where + std::to_string(column);
}

CompileResult compile_expression(std::string_view source, const CompileLimits& limits) {
    CompileResult result;
    if (source.size() > limits.max_source_bytes) {
        result.error =
            CompileError{"input too long: " + std::to_string(source.size()) +
                         " bytes, the limit is " + std::to_string(limits.max_source_bytes)};
        return result;
    }
    TapeBuilder builder;
    expr::Slot output = 0;
    result.error = expr::parse_equation(source, limits, builder, output);
    if (result.ok()) result.tape = builder.finish(output);
    return result;
}

}  // namespace isomesh
