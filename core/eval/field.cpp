#include <cassert>
#include <limits>

#include "eval/evaluator.h"

namespace isomesh {

void Evaluator::value_gradients(const PointBatch& points, std::span<ValueGradient> out) {
    assert(points.y.size() == points.size() && points.z.size() == points.size() &&
           out.size() == points.size());
    for (std::size_t i = 0; i < out.size(); ++i)
        out[i] = value_gradient({points.x[i], points.y[i], points.z[i]});
}

void Evaluator::intervals(std::span<const Box> boxes, std::span<IntervalValue> out) {
    assert(boxes.size() == out.size());
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = interval(boxes[i]);
}

void Evaluator::interval_gradients(std::span<const Box> boxes, std::span<IntervalGradient> out) {
    assert(boxes.size() == out.size());
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = interval_gradient(boxes[i]);
}

Box Field::domain() const {
    constexpr double kInf = std::numeric_limits<double>::infinity();
    return {glm::dvec3(-kInf), glm::dvec3(kInf)};
}

}  // namespace isomesh
