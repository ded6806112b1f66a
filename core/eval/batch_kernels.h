// The loops of the batch evaluator: one operation applied to a block of points held in
// structure-of-arrays registers (arrays of up to kBatchBlock doubles).
#pragma once

#include <cstddef>

#include "tape/tape.h"

namespace isomesh {

/// Points per block. A block's registers should stay in the first-level caches: prospero needs
/// a few dozen live registers at a time.
inline constexpr std::size_t kBatchBlock = 256;

/// out[i] = op(a[i], b[i]) for i < n, with an immediate operand in place of a or b as the form
/// says. Preconditions: n <= kBatchBlock; out overlaps neither a nor b.
using BatchKernel = void (*)(const double* a, const double* b, double imm, double* out,
                             std::size_t n);

enum class BatchForm {
    Registers,   // unary op(a[i]) (imm: PowInt's exponent), or binary op(a[i], b[i])
    ImmediateA,  // binary op(imm, b[i])
    ImmediateB,  // binary op(a[i], imm)
};

/// The kernel for `op` in `form`. Leaves: Const fills out with imm; VarX, VarY and VarZ copy a.
BatchKernel batch_kernel(Op op, BatchForm form);

}  // namespace isomesh
