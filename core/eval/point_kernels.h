// The fast point evaluator with gradient: forward-mode automatic differentiation of the
// register-allocated program (TapeProgram::steps) over W points at once, each register a structure
// of arrays, each step specialised to its operation (interval_kernels.h's machinery on numbers).
// W = 1 serves Evaluator::value_gradient, W = kPointLanes the batched value_gradients.
//
// Exactness: each lane computes what forward_mode::differentiate on double computes over the
// program's code, bit for bit (the same operations of op_math.h, the same derivative formulas,
// the same zero-tangent rule), so batches equal single points and both equal the reference.
#pragma once

#include <cstddef>
#include <span>

#include "eval/batch_kernels.h"

namespace isomesh {

/// Points per batch of the point-gradient kernels.
inline constexpr std::size_t kPointLanes = 8;

/// A register of the point forward-mode evaluator: a value and its gradient at W points.
template <std::size_t W>
struct alignas(8 * W) PointRegister {
    double value[W];
    double grad[3][W];
};

/// Runs `steps` in forward mode over W points: registers[0..2] hold x, y and z with the unit
/// vectors as gradients; the result lands in registers[kOutputRegister].
/// Precondition: no step writes a register it reads.
void run_point_gradient_steps(std::span<const BatchStep> steps, PointRegister<1>* registers);
void run_point_gradient_steps(std::span<const BatchStep> steps,
                              PointRegister<kPointLanes>* registers);

}  // namespace isomesh
