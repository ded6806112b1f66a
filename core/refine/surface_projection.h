// Moving a point onto the surface f = 0: the new vertex of every split, and every vertex again
// when the function changes.
#pragma once

#include <cstdint>

#include <glm/vec3.hpp>

#include "eval/evaluator.h"

namespace isomesh {

struct ProjectionSettings {
    /// Newton iterations before falling back to bracketing.
    int max_newton_steps = 10;
    /// Converged when the first-order distance |f| / |grad f| is below tolerance * scale.
    double tolerance = 1e-10;
    /// The projected point must stay within max_displacement * scale of the start.
    double max_displacement = 1.0;
    /// Points sampled on each side of the start along the search direction when Newton fails.
    int bracket_samples = 8;
};

enum class ProjectionMethod : std::uint8_t {
    Newton,      // converged by Newton's method along the gradient
    Bracketing,  // a sign change found along the search direction, refined by regula falsi
    Failed,      // no root found near the start: position is the start
};

struct Projection {
    glm::dvec3 position{0.0};
    /// Unit gradient at position (outward, towards f > 0); zero where it is not defined.
    glm::dvec3 normal{0.0};
    ProjectionMethod method = ProjectionMethod::Failed;
    int evaluations = 0;

    bool on_surface() const { return method != ProjectionMethod::Failed; }
};

/// Where and how to look for the surface near a point.
struct ProjectionRequest {
    glm::dvec3 start{0.0};
    /// Fallback search line start + t * direction, |t| <= max_displacement * scale, used when
    /// Newton fails (for an edge midpoint: the mean of the endpoint normals). Need not be unit.
    glm::dvec3 direction{0.0};
    /// The local feature size (for a split: the length of the bisected edge). Must be > 0.
    double scale = 1.0;
    /// An axis (0..2) whose coordinate must not change (a vertex on a face of the meshing box),
    /// or -1.
    int fixed_axis = -1;
};

/// Projects request.start onto f = 0. Newton's method along the gradient (steps clamped to the
/// search radius, rejected when f is undefined or the step leaves the radius); on failure,
/// bracketing: f sampled at growing distances on both sides along request.direction, the nearest
/// sign change refined by the Illinois variant of regula falsi, and rejected when |f| grows towards
/// the crossing (a pole such as 1/x, not a root). When both fail the start is returned, with
/// method Failed: a vertex is never moved to a pole or far off the surface.
Projection project_to_surface(Evaluator& evaluator, const ProjectionRequest& request,
                              const ProjectionSettings& settings = {});

}  // namespace isomesh
