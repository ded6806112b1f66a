// An Evaluator that counts the work it forwards to another one, for PolygonizeStats.
#pragma once

#include <cstddef>
#include <memory>
#include <utility>

#include "eval/evaluator.h"

namespace isomesh {

class CountingEvaluator final : public Evaluator {
  public:
    explicit CountingEvaluator(std::unique_ptr<Evaluator> inner) : inner_(std::move(inner)) {}

    double value(const glm::dvec3& p) override {
        ++points_;
        return inner_->value(p);
    }
    void values(const PointBatch& points, std::span<double> out) override {
        points_ += points.size();
        inner_->values(points, out);
    }
    IntervalValue interval(const Box& box) override {
        ++intervals_;
        return inner_->interval(box);
    }
    ValueGradient value_gradient(const glm::dvec3& p) override {
        ++points_;
        return inner_->value_gradient(p);
    }
    IntervalGradient interval_gradient(const Box& box) override {
        ++intervals_;
        return inner_->interval_gradient(box);
    }
    void value_gradients(const PointBatch& points, std::span<ValueGradient> out) override {
        points_ += points.size();
        inner_->value_gradients(points, out);
    }
    void intervals(std::span<const Box> boxes, std::span<IntervalValue> out) override {
        intervals_ += boxes.size();
        inner_->intervals(boxes, out);
    }
    void interval_gradients(std::span<const Box> boxes, std::span<IntervalGradient> out) override {
        intervals_ += boxes.size();
        inner_->interval_gradients(boxes, out);
    }
    void push(const Box& box) override { inner_->push(box); }
    void pop() override { inner_->pop(); }

    /// Point evaluations (value, values per point, value_gradient) so far.
    std::size_t point_evaluations() const { return points_; }
    /// Interval evaluations (interval, interval_gradient) so far.
    std::size_t interval_evaluations() const { return intervals_; }

  private:
    std::unique_ptr<Evaluator> inner_;
    std::size_t points_ = 0;
    std::size_t intervals_ = 0;
};

}  // namespace isomesh
