// The Field of a compiled tape: its evaluators run the four kinds of evaluation (point, batch,
// interval with interval gradient, value with gradient) over the same instructions, and support
// tape simplification on a box through Evaluator::push/pop.
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include "eval/evaluator.h"
#include "tape/tape.h"

namespace isomesh {

struct TapeFieldOptions {
    /// Evaluator::push(box) specialises the tape to the box (min/max branches proven irrelevant
    /// are dropped). When false, push and pop do nothing.
    bool simplify = true;
    /// Evaluate with the reference evaluation (reference_evaluation.h: the generic arithmetic, one
    /// instruction at a time) instead of the kernels: the same results, bit for bit, slower. For
    /// the tests and benchmarks that compare the two.
    bool reference = false;
};

/// The field f(x, y, z) computed by `tape` with parameter i bound to params[i]. Cheap to call
/// again with other parameter values: the tape is shared, not copied. Evaluators made by the
/// field may be used by one thread each, concurrently.
/// Throws std::invalid_argument (with a message saying what is wrong) when `tape` is null or
/// invalid (Tape::validate), when params.size() differs from tape->params.size(), or when a PowInt
/// exponent is not a whole number in [-2^30, 2^30].
std::shared_ptr<const Field> make_tape_field(std::shared_ptr<const Tape> tape,
                                             std::vector<double> params,
                                             TapeFieldOptions options = {});

/// The number of instructions `evaluator` currently runs: the tape's size, or less inside a
/// push() that simplified it. 0 when `evaluator` does not come from make_tape_field. For tests and
/// benchmarks.
std::size_t active_tape_size(const Evaluator& evaluator);

/// How many box-steps (one instruction on one box) `evaluator`'s interval kernels have run, and
/// how many of them the reference code recomputed (where an enclosure is not finite: poles,
/// infinite boxes, divisors holding 0; see interval_kernels.h). Zeros when `evaluator` does not
/// come from make_tape_field. For tests and benchmarks.
struct IntervalKernelCounts {
    std::size_t steps = 0;
    std::size_t by_reference = 0;
};
IntervalKernelCounts interval_kernel_counts(const Evaluator& evaluator);

}  // namespace isomesh
