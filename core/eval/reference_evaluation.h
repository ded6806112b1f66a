// Evaluation of a tape program's SSA code one instruction at a time with the generic arithmetic
// (tape_arithmetic.h, forward_mode.h): the semantics the fast kernels (interval_kernels.h,
// point_kernels.h) reproduce bit for bit. Kept as their reference (the tests compare the two, the
// benchmarks measure the gain; TapeFieldOptions::reference evaluates with it alone) and to
// recompute the rare lanes the interval kernels leave to it.
#pragma once

#include <span>
#include <vector>

#include "eval/evaluator.h"
#include "eval/forward_mode.h"
#include "eval/tape_program.h"
#include "eval/tape_simplify.h"

namespace isomesh {

class ReferenceEvaluation {
  public:
    double value(const TapeProgram& program, const glm::dvec3& p);
    ValueGradient value_gradient(const TapeProgram& program, const glm::dvec3& p);
    /// Also writes the choice proven at each of program.choice_slots to `choices`.
    /// Precondition: choices.size() == program.choice_slots.size().
    IntervalValue interval(const TapeProgram& program, const Box& box, std::span<Choice> choices);
    /// As interval(), with the gradient's enclosures.
    IntervalGradient interval_gradient(const TapeProgram& program, const Box& box,
                                       std::span<Choice> choices);

  private:
    std::vector<double> slots_;
    std::vector<IntervalValue> intervals_;
    std::vector<forward_mode::Tangent<double>> duals_;
    std::vector<forward_mode::Tangent<IntervalValue>> interval_duals_;
};

}  // namespace isomesh
