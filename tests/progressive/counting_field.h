// A field that counts every evaluation call its evaluators make, in one counter shared by all
// threads, and raises a cancel flag once the count reaches a threshold: budgets and cancellation
// points measured in evaluations rather than time, so the tests never depend on speed.
#pragma once

#include <atomic>
#include <cstdint>
#include <limits>
#include <memory>

#include "eval/evaluator.h"
#include "work/work_budget.h"

namespace isomesh::test {

struct EvaluationCounter {
    std::atomic<std::int64_t> calls{0};
    std::atomic<bool> cancel{false};
    std::int64_t cancel_at = std::numeric_limits<std::int64_t>::max();
    std::atomic<std::int64_t> calls_when_cancelled{-1};

    void count() {
        const std::int64_t now = ++calls;
        if (now >= cancel_at && !cancel.exchange(true)) calls_when_cancelled = now;
    }
    /// A clock for WorkBudget whose unit is one evaluation call.
    WorkBudget::Clock clock() {
        return [this] { return calls.load(); };
    }
};

class CountingField final : public Field {
  public:
    CountingField(std::shared_ptr<const Field> inner, std::shared_ptr<EvaluationCounter> counter)
        : inner_(std::move(inner)), counter_(std::move(counter)) {}

    std::unique_ptr<Evaluator> make_evaluator() const override {
        return std::make_unique<Counting>(inner_->make_evaluator(), counter_);
    }
    Box domain() const override { return inner_->domain(); }

  private:
    class Counting final : public Evaluator {
      public:
        Counting(std::unique_ptr<Evaluator> inner, std::shared_ptr<EvaluationCounter> counter)
            : inner_(std::move(inner)), counter_(std::move(counter)) {}
        double value(const glm::dvec3& p) override {
            counter_->count();
            return inner_->value(p);
        }
        void values(const PointBatch& points, std::span<double> out) override {
            counter_->count();
            inner_->values(points, out);
        }
        IntervalValue interval(const Box& box) override {
            counter_->count();
            return inner_->interval(box);
        }
        ValueGradient value_gradient(const glm::dvec3& p) override {
            counter_->count();
            return inner_->value_gradient(p);
        }
        IntervalGradient interval_gradient(const Box& box) override {
            counter_->count();
            return inner_->interval_gradient(box);
        }
        void value_gradients(const PointBatch& points, std::span<ValueGradient> out) override {
            counter_->count();
            inner_->value_gradients(points, out);
        }
        void intervals(std::span<const Box> boxes, std::span<IntervalValue> out) override {
            counter_->count();
            inner_->intervals(boxes, out);
        }
        void interval_gradients(std::span<const Box> boxes,
                                std::span<IntervalGradient> out) override {
            counter_->count();
            inner_->interval_gradients(boxes, out);
        }
        void push(const Box& box) override { inner_->push(box); }
        void pop() override { inner_->pop(); }

      private:
        std::unique_ptr<Evaluator> inner_;
        std::shared_ptr<EvaluationCounter> counter_;
    };

    std::shared_ptr<const Field> inner_;
    std::shared_ptr<EvaluationCounter> counter_;
};

}  // namespace isomesh::test
