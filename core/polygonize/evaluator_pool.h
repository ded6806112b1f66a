// The threads of one polygonization's parallel loops, each with its own evaluator of the field
// (the libfive and Fidget model: evaluators hold scratch memory and serve one thread). The loops
// run on the caller's thread and on helpers (work/helpers.h): an executor's idle threads (a
// server's workers), or threads started for each loop when no executor is given.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <vector>

#include "eval/evaluator.h"
#include "polygonize/counting_evaluator.h"
#include "work/helpers.h"

namespace isomesh {

/// Tasks of at most `per_task` items each for `items` items.
inline std::size_t task_count(std::size_t items, std::size_t per_task) {
    return (items + per_task - 1) / per_task;
}

class EvaluatorPool {
  public:
    /// Up to `threads` >= 1 threads a loop (the caller and threads - 1 helpers), on evaluators
    /// made by `field` (which must outlive the pool); `helpers` may be null (see above). The
    /// caller's evaluator is made now, a helper's the first time a helper takes its slot: a
    /// polygonization no executor thread helps holds one evaluator.
    EvaluatorPool(const Field& field, int threads, Helpers* helpers = nullptr);

    int size() const { return static_cast<int>(evaluators_.size()); }
    /// Evaluators made so far (the caller's and those of the slots helpers took). Not while a
    /// for_each runs.
    std::size_t evaluators_made() const;

    /// Runs task(i, evaluator) for every i in [0, count), the indices handed out dynamically to
    /// the threads (the caller's is one of them). Determinism is the caller's part: a task must
    /// depend on i only and store its results by i. Rethrows the first exception a task threw.
    void for_each(std::size_t count,
                  const std::function<void(std::size_t, CountingEvaluator&)>& task);

    /// Totals over the evaluators. Not while a for_each runs.
    std::size_t point_evaluations() const;
    std::size_t interval_evaluations() const;

  private:
    /// The evaluator of `slot` (work/helpers.h), made on first use. Only the thread holding the
    /// slot in the loop under way touches it; run_helped's join orders loops.
    CountingEvaluator& evaluator(unsigned slot);

    const Field& field_;
    Helpers* helpers_;
    std::vector<std::unique_ptr<CountingEvaluator>> evaluators_;  // by slot; null until used
};

}  // namespace isomesh
