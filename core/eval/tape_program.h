// A tape prepared for evaluation: parameters bound to their values, and a register-allocated form
// of the same instructions for the batch evaluator.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "eval/batch_kernels.h"
#include "tape/tape.h"

namespace isomesh {

/// Batch registers: x, y and z of the block's points, the caller's output array, then scratch.
inline constexpr std::uint32_t kOutputRegister = 3;
inline constexpr std::uint32_t kFirstScratchRegister = 4;

struct TapeProgram {
    /// SSA code as in a Tape, with no Param instruction (bound to Const).
    std::vector<Instruction> code;
    /// The live instructions with registers assigned by a linear scan over last uses (a register
    /// is reused once its value is dead), constants folded into immediate operands. The last step
    /// writes kOutputRegister.
    std::vector<BatchStep> steps;
    std::uint32_t scratch_registers = 0;
    /// The live min, max and logsumexp instructions (indices into `code`), in order: interval
    /// evaluation records a Choice for each (tape_simplify.h), which simplification on a box
    /// prunes by.
    std::vector<std::uint32_t> choice_slots;
    /// True when every immediate operand of `steps` is finite: the interval kernels
    /// (interval_kernels.h) treat an immediate c as the interval [c, c], which a NaN or an
    /// infinity is not in the reference arithmetic.
    bool finite_immediates = true;
};

/// The code of `tape` with each Param instruction replaced by a Const of its value.
/// Precondition: tape.validate() is empty and params.size() == tape.params.size().
std::vector<Instruction> substitute_parameters(const Tape& tape, std::span<const double> params);

/// Prepares `code` (a valid SSA tape without Param instructions) for evaluation.
TapeProgram make_program(std::vector<Instruction> code);

}  // namespace isomesh
