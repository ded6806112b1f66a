#include "polygonize/evaluator_pool.h"

#include <algorithm>
#include <atomic>
#include <cassert>
#include <exception>
#include <mutex>
#include <thread>

namespace isomesh {

EvaluatorPool::EvaluatorPool(const Field& field, int threads) {
    assert(threads >= 1);
    for (int i = 0; i < threads; ++i) {
        evaluators_.push_back(std::make_unique<CountingEvaluator>(field.make_evaluator()));
    }
}

void EvaluatorPool::for_each(std::size_t count,
                             const std::function<void(std::size_t, CountingEvaluator&)>& task) {
    std::atomic<std::size_t> next{0};
    std::exception_ptr error;
    std::mutex error_mutex;
    auto work = [&](CountingEvaluator& evaluator) {
        for (std::size_t i = next++; i < count; i = next++) {
            try {
                task(i, evaluator);
            } catch (...) {
                const std::lock_guard lock(error_mutex);
                if (!error) error = std::current_exception();
                next = count;  // stop handing out work
            }
        }
    };
    const std::size_t helpers =
        std::min<std::size_t>(evaluators_.size() - 1, count > 0 ? count - 1 : 0);
    std::vector<std::jthread> threads;
    threads.reserve(helpers);
    for (std::size_t w = 1; w <= helpers; ++w) {
        threads.emplace_back([&work, this, w] { work(*evaluators_[w]); });
    }
    work(*evaluators_[0]);
    threads.clear();  // joins
    if (error) std::rethrow_exception(error);
}

std::size_t EvaluatorPool::point_evaluations() const {
    std::size_t total = 0;
    for (const auto& e : evaluators_) total += e->point_evaluations();
    return total;
}

std::size_t EvaluatorPool::interval_evaluations() const {
    std::size_t total = 0;
    for (const auto& e : evaluators_) total += e->interval_evaluations();
    return total;
}

}  // namespace isomesh
