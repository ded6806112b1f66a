// Grid, normals and split predictions of version-2 deltas (see delta_v2_geometry.h).
#include "protocol/delta_v2_geometry.h"

#include <algorithm>
#include <cmath>

namespace isomesh::protocol {
namespace {

double sign_of(double x) {
    return x >= 0.0 ? 1.0 : -1.0;
}

}  // namespace

GridMath::GridMath(const QuantizationGrid& grid)
    : grid_(grid),
      max_((std::int64_t{1} << grid.position_bits) - 1),
      octahedral_((std::int64_t{1} << (grid.normal_bits - 1)) - 1),
      delta_(grid.range / static_cast<float>(max_)),
      inverse_delta_(static_cast<float>(max_) / grid.range) {}

GridPoint GridMath::quantize(const glm::vec3& position) const {
    GridPoint q{};
    for (int axis = 0; axis < 3; ++axis) {
        const float low = grid_.origin[axis];
        const float x = std::clamp(position[axis], low, low + grid_.range);
        const float value = (x - low) * inverse_delta_;
        q[axis] =
            std::clamp<std::int64_t>(static_cast<std::int64_t>(std::floor(value + 0.5f)), 0, max_);
    }
    return q;
}

glm::vec3 GridMath::dequantize(const GridPoint& q) const {
    glm::vec3 p;
    for (int axis = 0; axis < 3; ++axis) {
        p[axis] = static_cast<float>(q[axis]) * delta_ + grid_.origin[axis];
    }
    return p;
}

GridPoint GridMath::recover(const glm::vec3& position) const {
    GridPoint q{};
    for (int axis = 0; axis < 3; ++axis) {
        const double offset = static_cast<double>(position[axis]) - grid_.origin[axis];
        q[axis] = static_cast<std::int64_t>(std::floor(offset / static_cast<double>(delta_) + 0.5));
    }
    return q;
}

OctNormal GridMath::encode_normal(const glm::dvec3& n) const {
    const double s = std::abs(n.x) + std::abs(n.y) + std::abs(n.z);
    if (!(s > 0.0) || !std::isfinite(s)) return {octahedral_, 0};
    double x = n.x / s;
    double y = n.y / s;
    if (n.z < 0.0) {
        const double folded_x = (1.0 - std::abs(y)) * sign_of(x);
        const double folded_y = (1.0 - std::abs(x)) * sign_of(y);
        x = folded_x;
        y = folded_y;
    }
    const auto m = static_cast<double>(octahedral_);
    return {static_cast<std::int64_t>(std::floor(x * m + 0.5)),
            static_cast<std::int64_t>(std::floor(y * m + 0.5))};
}

glm::vec3 GridMath::decode_normal(const OctNormal& code) const {
    const auto m = static_cast<double>(octahedral_);
    double x = static_cast<double>(code[0]) / m;
    double y = static_cast<double>(code[1]) / m;
    const double z = 1.0 - std::abs(x) - std::abs(y);
    if (z < 0.0) {
        const double folded_x = (1.0 - std::abs(y)) * sign_of(x);
        const double folded_y = (1.0 - std::abs(x)) * sign_of(y);
        x = folded_x;
        y = folded_y;
    }
    const double length = std::sqrt(x * x + y * y + z * z);
    return glm::vec3(static_cast<float>(x / length), static_cast<float>(y / length),
                     static_cast<float>(z / length));
}

GridPoint GridMath::predict_split(const GridPoint& p, const GridPoint& q, const glm::vec3& np,
                                  const glm::vec3& nq) const {
    double d = static_cast<double>(p[0] - q[0]) * (static_cast<double>(np.x) - nq.x);
    d = d + static_cast<double>(p[1] - q[1]) * (static_cast<double>(np.y) - nq.y);
    d = d + static_cast<double>(p[2] - q[2]) * (static_cast<double>(np.z) - nq.z);
    d = d / 8.0;
    GridPoint out{};
    for (int axis = 0; axis < 3; ++axis) {
        const double bend = (static_cast<double>(np[axis]) + nq[axis]) * d;
        const double twice = static_cast<double>(p[axis] + q[axis]) + bend;
        const double value = std::floor(twice * 0.5 + 0.5);
        out[axis] = static_cast<std::int64_t>(std::clamp(value, 0.0, static_cast<double>(max_)));
    }
    return out;
}

OctNormal GridMath::predict_normal(const glm::vec3& np, const glm::vec3& nq) const {
    return encode_normal(glm::dvec3(np) + glm::dvec3(nq));
}

GridPoint GridMath::predict_move(const GridPoint& p, const glm::vec3& n, std::int64_t steps) const {
    GridPoint out{};
    for (int axis = 0; axis < 3; ++axis) {
        const double moved = static_cast<double>(p[axis]) +
                             static_cast<double>(n[axis]) * static_cast<double>(steps);
        const double value = std::floor(moved + 0.5);
        out[axis] = static_cast<std::int64_t>(std::clamp(value, 0.0, static_cast<double>(max_)));
    }
    return out;
}

bool GridMath::valid(const GridPoint& q) const {
    return std::all_of(q.begin(), q.end(), [&](std::int64_t c) { return c >= 0 && c <= max_; });
}

bool GridMath::valid(const OctNormal& n) const {
    return std::all_of(n.begin(), n.end(),
                       [&](std::int64_t c) { return c >= -octahedral_ && c <= octahedral_; });
}

}  // namespace isomesh::protocol
