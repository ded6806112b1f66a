// The fast interval evaluators: a register-allocated program (TapeProgram::steps) run over W boxes
// at once, each register a structure of arrays with one lane per box, each step specialised to its
// operation and operand form at compile time (no per-operation call, no IntervalValue temporaries).
// W = 1 serves single boxes, W = kIntervalLanes an octree cell's children: the same source, its
// lane type a double or a vector of W doubles (GCC and clang vector extensions), so the arithmetic
// runs on all lanes at once.
//
// Exactness. The kernels compute what the reference arithmetic (interval_math.h, forward_mode.h
// on IntervalValue) computes, bit for bit, flags and choices included. Operations other than the
// common arithmetic run the reference code itself per lane (interval_ranges.h, inlined for the
// operation). The common ones (+ - * / neg square abs sqrt powers min max, and the derivative
// rules) use branch-free formulas that equal the reference's whenever their operands are finite:
// the reference's special cases (empty operands, infinities, 0 * inf) all involve a non-finite
// operand. Each register lane carries a bit saying whether it holds a non-finite enclosure; a step
// recomputes the lanes whose operands (or partial derivatives) are not finite, and the few finite
// cases the formulas leave out (a divisor holding 0, the square root of a negative interval), with
// the reference code for that one operation.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "eval/batch_kernels.h"
#include "eval/tape_simplify.h"

namespace isomesh {

/// Boxes per batch of the interval kernels: an octree cell's children.
inline constexpr std::size_t kIntervalLanes = 8;
/// Boxes per batch of the narrower kernels, for a few boxes (a cell's faces, an edge's halves, the
/// last of a cell's 12 edges): one vector of lanes, at about the cost of one box.
inline constexpr std::size_t kIntervalFewLanes = 4;

/// IntervalValue's flags as bits, one integer per lane.
inline constexpr std::int64_t kMaybeDiscontinuous = 1;
inline constexpr std::int64_t kMaybeUndefined = 2;

/// A register of the interval evaluator: enclosures of one value over W boxes, with their flags.
template <std::size_t W>
struct alignas(8 * W) IntervalRegister {
    double lo[W];
    double hi[W];
    std::int64_t flags[W];
};

/// A register of the interval forward-mode evaluator: enclosures of one value and of its gradient
/// over W boxes.
template <std::size_t W>
struct alignas(8 * W) GradientRegister {
    double lo[W];
    double hi[W];
    std::int64_t flags[W];
    double grad_lo[3][W];
    double grad_hi[3][W];
};

/// Runs `steps` over W boxes: registers[0..2] hold x, y and z with no flags (and the unit vectors
/// as their gradients), the result lands in registers[kOutputRegister] (its flags may hold bits
/// besides IntervalValue's: test each). The choice proven at the i-th min or max step for lane l
/// goes to choices[l * choice_count + i]. Results and choices equal the reference's bit for bit.
/// Returns how many lane-steps ran the reference code (see the file comment).
/// Preconditions: every immediate of `steps` is finite (TapeProgram::finite_immediates); no step
/// writes a register it reads; choice_count is the number of min and max steps.
std::size_t run_interval_steps(std::span<const BatchStep> steps, IntervalRegister<1>* registers,
                               Choice* choices, std::size_t choice_count);
std::size_t run_interval_steps(std::span<const BatchStep> steps,
                               IntervalRegister<kIntervalFewLanes>* registers, Choice* choices,
                               std::size_t choice_count);
std::size_t run_interval_steps(std::span<const BatchStep> steps,
                               IntervalRegister<kIntervalLanes>* registers, Choice* choices,
                               std::size_t choice_count);
std::size_t run_gradient_steps(std::span<const BatchStep> steps, GradientRegister<1>* registers,
                               Choice* choices, std::size_t choice_count);
std::size_t run_gradient_steps(std::span<const BatchStep> steps,
                               GradientRegister<kIntervalFewLanes>* registers, Choice* choices,
                               std::size_t choice_count);
std::size_t run_gradient_steps(std::span<const BatchStep> steps,
                               GradientRegister<kIntervalLanes>* registers, Choice* choices,
                               std::size_t choice_count);

}  // namespace isomesh
