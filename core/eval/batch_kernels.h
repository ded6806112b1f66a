// The loops of the batch evaluator: a straight-line program run over one block of points at a
// time, each register an array of up to kBatchBlock doubles (structure of arrays).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "tape/tape.h"

/// Compiles a function also for AVX2 and picks the version at load time (GCC on x86-64; AVX2
/// without FMA rounds exactly as SSE2). For the batch loops, and for the native baselines the
/// benchmark compares them with.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define ISOMESH_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define ISOMESH_VECTOR_CLONES
#endif

namespace isomesh {

/// Points per block: long enough to amortise dispatching each step, short enough that the live
/// registers of a big model (prospero: 127) stay in the second-level cache.
inline constexpr std::size_t kBatchBlock = 256;

enum class BatchForm : std::uint8_t {
    Registers,   // unary op(a[i]) (imm: PowInt's exponent), or binary op(a[i], b[i])
    ImmediateA,  // binary op(imm, b[i])
    ImmediateB,  // binary op(a[i], imm)
};

/// One step: register out = op(register a, register b) over the block, with imm in place of an
/// operand as `form` says. Leaves: Const fills out with imm; VarX, VarY and VarZ copy register a.
struct BatchStep {
    Op op;
    BatchForm form;
    std::uint32_t out;
    std::uint32_t a;
    std::uint32_t b;
    double imm;
};

/// Runs `steps` in order over one block of n points. read[r] and write[r] are register r's array
/// (both the same array for a scratch register).
/// Preconditions: n <= kBatchBlock; a step's output array overlaps none of its operand arrays.
void run_batch_steps(std::span<const BatchStep> steps, const double* const* read,
                     double* const* write, std::size_t n);

/// The points of run_small_batch_steps.
inline constexpr std::size_t kSmallBatch = 8;

/// run_batch_steps over exactly kSmallBatch points, a count known at compile time: loops without
/// the remainders of a general count (the refiner's error measure evaluates 8 points at a time,
/// very often). The same values.
void run_small_batch_steps(std::span<const BatchStep> steps, const double* const* read,
                           double* const* write);

/// run_batch_steps for a single point, with the same operations of op_math.h (bit-identical
/// values): registers[r] is register r; registers 0-2 hold x, y and z.
void run_point_steps(std::span<const BatchStep> steps, double* registers);

}  // namespace isomesh
