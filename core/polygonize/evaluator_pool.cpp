#include "polygonize/evaluator_pool.h"

#include <algorithm>
#include <atomic>
#include <cassert>
#include <exception>
#include <mutex>

namespace isomesh {

EvaluatorPool::EvaluatorPool(const Field& field, int threads, Helpers* helpers)
    : field_(field), helpers_(helpers), evaluators_(static_cast<std::size_t>(threads)) {
    assert(threads >= 1);
    evaluator(0);
}

CountingEvaluator& EvaluatorPool::evaluator(unsigned slot) {
    assert(slot < evaluators_.size());
    auto& e = evaluators_[slot];
    if (!e) e = std::make_unique<CountingEvaluator>(field_.make_evaluator());
    return *e;
}

void EvaluatorPool::for_each(std::size_t count,
                             const std::function<void(std::size_t, CountingEvaluator&)>& task) {
    std::atomic<std::size_t> next{0};
    std::exception_ptr error;
    std::mutex error_mutex;
    const HelpWork work = [&](unsigned slot, const Recall& recalled) {
        CountingEvaluator* e = nullptr;  // made at the first item: a helper may find none left
        std::size_t items = 0;
        while (!recalled()) {
            const std::size_t i = next++;
            if (i >= count) break;
            try {
                if (e == nullptr) e = &evaluator(slot);
                task(i, *e);
            } catch (...) {
                const std::lock_guard lock(error_mutex);
                if (!error) error = std::current_exception();
                next = count;  // stop handing out work
            }
            ++items;
        }
        return items;
    };
    const std::size_t helpers =
        std::min<std::size_t>(evaluators_.size() - 1, count > 0 ? count - 1 : 0);
    run_helped(helpers_, static_cast<unsigned>(helpers), work);
    if (error) std::rethrow_exception(error);
}

std::size_t EvaluatorPool::evaluators_made() const {
    return static_cast<std::size_t>(std::count_if(evaluators_.begin(), evaluators_.end(),
                                                  [](const auto& e) { return e != nullptr; }));
}

std::size_t EvaluatorPool::point_evaluations() const {
    std::size_t total = 0;
    for (const auto& e : evaluators_) total += e ? e->point_evaluations() : 0;
    return total;
}

std::size_t EvaluatorPool::interval_evaluations() const {
    std::size_t total = 0;
    for (const auto& e : evaluators_) total += e ? e->interval_evaluations() : 0;
    return total;
}

}  // namespace isomesh
