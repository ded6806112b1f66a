// Newton projection onto an implicit surface (the thesis's projection step, 3.1.4 "Projection",
// with the analytic gradient instead of differences): the first-order model
// f(p + s) ~ f(p) + grad f(p) . s is solved for the shortest step s, which is along the gradient.
// Damping (step halving while |f| does not decrease) and clipping to the cell keep the iteration
// in the cell whose triangulation placed the point.
#include "polygonize/vertex_projection.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

#include "polygonize/edge_roots.h"
#include "polygonize/lattice.h"

namespace isomesh {
namespace {

constexpr int kMaxIterations = 50;
constexpr int kMaxHalvings = 30;
constexpr double kTolerance = 1e-14;

/// The largest fraction of `step` that keeps p + fraction * step inside `bounds`.
double fraction_inside(const glm::dvec3& p, const glm::dvec3& step, const Box& bounds) {
    double fraction = 1.0;
    for (int axis = 0; axis < 3; ++axis) {
        if (step[axis] > 0.0) {
            fraction = std::min(fraction, (bounds.hi[axis] - p[axis]) / step[axis]);
        } else if (step[axis] < 0.0) {
            fraction = std::min(fraction, (bounds.lo[axis] - p[axis]) / step[axis]);
        }
    }
    return std::max(fraction, 0.0);
}

glm::dvec3 clamp_to(const glm::dvec3& p, const Box& bounds) {
    return glm::clamp(p, bounds.lo, bounds.hi);
}

SurfacePoint evaluate(Evaluator& evaluator, const glm::dvec3& p) {
    const ValueGradient vg = evaluator.value_gradient(p);
    return {vg.value == 0.0, p, vg.value, vg.gradient};
}

bool close_enough(const SurfacePoint& s, double tolerance) {
    const double g = glm::length(s.gradient);
    return s.value == 0.0 || (g > 0.0 && std::abs(s.value) <= tolerance * g);
}

SurfacePoint newton(Evaluator& evaluator, const glm::dvec3& start, const Box& bounds,
                    double tolerance) {
    SurfacePoint current = evaluate(evaluator, clamp_to(start, bounds));
    for (int iteration = 0; iteration < kMaxIterations; ++iteration) {
        if (close_enough(current, tolerance)) {
            current.on_surface = true;
            return current;
        }
        const double g2 = glm::dot(current.gradient, current.gradient);
        if (!(g2 > 0.0) || !std::isfinite(current.value)) return current;
        glm::dvec3 step = -current.value / g2 * current.gradient;
        step *= fraction_inside(current.position, step, bounds);
        bool improved = false;
        for (int h = 0; h < kMaxHalvings && !improved; ++h, step *= 0.5) {
            const SurfacePoint next =
                evaluate(evaluator, clamp_to(current.position + step, bounds));
            if (std::abs(next.value) < std::abs(current.value)) {
                current = next;
                improved = true;
            }
        }
        if (!improved) return current;
    }
    return current;
}

/// The root on the segment from `from` to the nearest corner of `bounds` on the other side.
SurfacePoint bracket_from_corner(Evaluator& evaluator, const SurfacePoint& from,
                                 const Box& bounds) {
    const bool inside = is_inside(from.value);
    double nearest = std::numeric_limits<double>::infinity();
    SurfacePoint result = from;
    for (int c = 0; c < 8; ++c) {
        const glm::dvec3 corner{(c & 1) ? bounds.hi.x : bounds.lo.x,
                                (c & 2) ? bounds.hi.y : bounds.lo.y,
                                (c & 4) ? bounds.hi.z : bounds.lo.z};
        const double distance = glm::distance(corner, from.position);
        if (distance >= nearest) continue;
        const double value = evaluator.value(corner);
        if (is_inside(value) == inside) continue;
        const EdgeRoot root =
            find_edge_root(evaluator, {from.position, corner, from.value, value, -1});
        if (!root.found) continue;
        nearest = distance;
        result = {true, root.position, root.value, root.gradient};
    }
    return result;
}

}  // namespace

SurfacePoint project_to_surface(Evaluator& evaluator, const glm::dvec3& start, const Box& bounds) {
    const double tolerance = kTolerance * glm::length(bounds.size());
    const SurfacePoint point = newton(evaluator, start, bounds, tolerance);
    if (point.on_surface || !std::isfinite(point.value)) return point;
    return bracket_from_corner(evaluator, point, bounds);
}

}  // namespace isomesh
