// Worker threads for one polygonization, each with its own evaluator of the field (the libfive and
// Fidget model: evaluators hold scratch memory and serve one thread).
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <vector>

#include "eval/evaluator.h"
#include "polygonize/counting_evaluator.h"

namespace isomesh {

class EvaluatorPool {
  public:
    /// threads >= 1 evaluators made by `field`.
    EvaluatorPool(const Field& field, int threads);

    int size() const { return static_cast<int>(evaluators_.size()); }

    /// Runs task(i, evaluator) for every i in [0, count), the indices handed out dynamically to
    /// the workers (the caller's thread is one of them). Determinism is the caller's part: a task
    /// must depend on i only and store its results by i. Rethrows the first exception a task threw.
    void for_each(std::size_t count,
                  const std::function<void(std::size_t, CountingEvaluator&)>& task);

    /// Totals over the workers' evaluators.
    std::size_t point_evaluations() const;
    std::size_t interval_evaluations() const;

  private:
    std::vector<std::unique_ptr<CountingEvaluator>> evaluators_;
};

}  // namespace isomesh
