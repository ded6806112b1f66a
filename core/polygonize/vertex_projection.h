// Moving a point onto the surface f = 0 along the gradient, inside a box.
#pragma once

#include <glm/vec3.hpp>

#include "eval/evaluator.h"

namespace isomesh {

struct SurfacePoint {
    /// False when no point of the surface was reached (the result is then the best point seen).
    bool on_surface = false;
    glm::dvec3 position{0.0};
    double value = 0.0;
    glm::dvec3 gradient{0.0};
};

/// Newton projection along the gradient, p <- p - f(p) grad f(p) / |grad f(p)|^2, from `start`
/// (inside `bounds`), each step clipped to `bounds` and halved while it does not decrease |f|.
/// Converged when |f| / |grad f| <= 1e-14 of the box's diagonal. If Newton fails (a flat or
/// discontinuous spot, or the surface out of reach inside the box), the root is sought instead on
/// the segment from the best point found to the nearest corner of `bounds` on the other side of
/// the surface (find_edge_root), which stays inside the box.
SurfacePoint project_to_surface(Evaluator& evaluator, const glm::dvec3& start, const Box& bounds);

}  // namespace isomesh
