// Moving a point onto the surface f = 0: the new vertex of every split, and every vertex again
// when the function changes.
#pragma once

#include <cstdint>
#include <limits>
#include <span>

#include <glm/vec3.hpp>

#include "eval/evaluator.h"

namespace isomesh {

struct ProjectionSettings {
    /// Secant iterations along the search direction, before Newton's method along the gradient.
    int max_secant_steps = 6;
    /// Newton iterations before falling back to bracketing.
    int max_newton_steps = 10;
    /// Converged when the first-order distance |f| / |grad f| is below tolerance * scale.
    double tolerance = 1e-9;
    /// The projected point must stay within max_displacement * scale of the start.
    double max_displacement = 1.0;
    /// Points sampled on each side of the start along the search direction when Newton fails.
    int bracket_samples = 8;
};

enum class ProjectionMethod : std::uint8_t {
    Secant,      // converged by secant iterations along the search direction
    Newton,      // converged by Newton's method along the gradient
    Bracketing,  // a sign change found along the search direction, refined by regula falsi
    Failed,      // no root found near the start: position is the start
};

struct Projection {
    glm::dvec3 position{0.0};
    /// Unit gradient at position (outward, towards f > 0); zero where it is not defined.
    glm::dvec3 normal{0.0};
    /// |grad f| at position (0 where it is not defined).
    double gradient_norm = 0.0;
    ProjectionMethod method = ProjectionMethod::Failed;
    int evaluations = 0;  // point evaluations of f (with or without gradient)

    bool on_surface() const { return method != ProjectionMethod::Failed; }
};

/// Where and how to look for the surface near a point.
struct ProjectionRequest {
    glm::dvec3 start{0.0};
    /// The search line start + t * direction, |t| <= max_displacement * scale (for an edge
    /// midpoint: the mean of the endpoint normals; for a vertex moving to a new surface: its old
    /// normal). Need not be unit; zero means none.
    glm::dvec3 direction{0.0};
    /// |grad f| near the start if known (the slope of f along a good direction), else 0.
    double slope = 0.0;
    /// The local feature size (for a split: the length of the bisected edge). Must be > 0.
    double scale = 1.0;
    /// The axes whose coordinates must not change (bit k for axis k): a vertex on a face of the
    /// meshing box keeps that face's coordinate, one on an edge of the box both (it moves along
    /// the box's edge), 0 for none.
    std::uint8_t fixed_axes = 0;
    /// f(start) when the caller evaluated it already (the refiner's error measure samples an edge
    /// midpoint before the midpoint is projected), else NaN: it saves the first evaluation.
    double start_value = std::numeric_limits<double>::quiet_NaN();
};

/// Projects request.start onto f = 0, in up to three stages, each rejected when f is undefined or
/// a step leaves the search radius:
/// 1. secant iterations on f along request.direction, started with request.slope: plain
///    evaluations of f, several times cheaper than with the gradient, then the gradient at the
///    last point to check the distance |f| / |grad f| and get the normal (evaluated with the last
///    value where the search expects that value to end it);
/// 2. Newton's method along the gradient, from the start;
/// 3. bracketing: f sampled at growing distances on both sides along request.direction, the
///    nearest sign change refined by the Illinois variant of regula falsi, and rejected when |f|
///    grows towards the crossing (a pole such as 1/x, not a root).
/// When all fail the start is returned, with method Failed: a vertex is never moved to a pole or
/// far off the surface.
Projection project_to_surface(Evaluator& evaluator, const ProjectionRequest& request,
                              const ProjectionSettings& settings = {});

/// out[i] = project_to_surface(evaluator, requests[i], settings), bit for bit, with the secant
/// stages of all requests run in lockstep on batched evaluations (Evaluator::values and
/// value_gradients). Precondition: requests.size() == out.size().
void project_to_surface(Evaluator& evaluator, std::span<const ProjectionRequest> requests,
                        std::span<Projection> out, const ProjectionSettings& settings = {});

/// The secant stage of a projection as a state machine fed one value of f at a time, so that
/// many can advance together on batched evaluations.
///
/// The point the search ends on is checked with the gradient there. Where the next value is
/// likely to end the search, wants_gradient() asks for it with the gradient (one evaluation
/// instead of two; the value is the same bit for bit): the secant method's residuals shrink
/// superlinearly, so the next one is predicted from the last two.
class SecantSearch {
  public:
    /// Starts from request.start_value when it is known (not NaN).
    SecantSearch(const ProjectionRequest& request, const ProjectionSettings& settings);
    bool wants_value() const { return phase_ == Phase::Start || phase_ == Phase::Iterating; }
    /// The next value should come with the gradient (feed(const ValueGradient&)).
    bool wants_gradient() const { return wants_gradient_; }
    /// Where f is wanted next. Precondition: wants_value().
    glm::dvec3 next_point() const { return phase_ == Phase::Start ? start_ : point(); }
    void feed(double f);
    /// feed(vg.value), keeping the gradient for the check of the point the search ends on.
    void feed(const ValueGradient& vg);
    /// The search ended on a candidate point (to be checked with the gradient).
    bool found() const { return phase_ == Phase::Found; }
    glm::dvec3 point() const { return start_ + t1_ * direction_; }
    /// f and grad f at point() when the search ended there on a value fed with the gradient
    /// (bit for bit the point evaluated), else nullptr.
    const ValueGradient* found_gradient() const {
        return found() && gradient_at_point_ ? &gradient_ : nullptr;
    }
    /// f at the start, or NaN before it was fed.
    double start_value() const { return start_value_; }
    /// Evaluations of f made for the search (a known start value is not one).
    int evaluations() const { return evaluations_; }

  private:
    enum class Phase : std::uint8_t { Start, Iterating, Found, Failed };
    /// step(f), then whether the next value should come with the gradient.
    void advance(double f);
    void step(double f);
    bool predicts_last_value() const;

    glm::dvec3 start_;
    glm::dvec3 direction_;
    double slope_;
    double radius_;
    double tolerance_;
    int max_steps_;
    Phase phase_ = Phase::Failed;
    int steps_ = 0;
    int evaluations_ = 0;
    double t0_ = 0.0, t0_f_ = 0.0, t1_ = 0.0;
    // The point before t0_ and f there (NaN: none yet).
    double previous_t_ = 0.0;
    double previous_f_ = std::numeric_limits<double>::quiet_NaN();
    double start_value_ = std::numeric_limits<double>::quiet_NaN();
    bool wants_gradient_ = false;
    bool gradient_at_point_ = false;
    ValueGradient gradient_;
};

}  // namespace isomesh
