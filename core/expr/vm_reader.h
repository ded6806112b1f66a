// Reader of Fidget's `.vm` models (https://github.com/mkeeter/fidget): straight-line programs,
// one instruction per line, `NAME OPCODE OPERANDS...`, `#` to the end of a line is a comment, blank
// lines are skipped, and the last instruction's value is the function (negative inside).
//
// Opcodes: `var-x var-y var-z`, `const C`; unary `neg square sqrt cbrt abs sgn floor ceil round exp
// ln lg ld sin cos tan asin acos atan sinh cosh tanh recip`; binary `add sub mul div pow atan2 min
// max` and Fidget's two-operand `atan` (= atan2), first operand on the left. The instructions go
// through the same TapeBuilder as typed expressions, so constants fold and repeats are shared.
#pragma once

#include <string_view>

#include "expr/compile.h"

namespace isomesh {

/// Compiles a .vm program. Errors give the 1-based line and, where one token is at fault, its
/// 1-based column (in bytes): unknown opcode, undefined or redefined name, wrong operand count,
/// bad or non-finite number, no instructions, and the limits `max_vm_bytes` and
/// `max_instructions` (counted as lines holding an instruction).
CompileResult read_vm(std::string_view text, const CompileLimits& limits = {});

}  // namespace isomesh
