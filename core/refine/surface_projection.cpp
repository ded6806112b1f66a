// Projection onto an implicit surface: Newton's method along the gradient (the thesis, section 4.1:
// "Newton's method in the gradient direction"), made robust by a bracketing fallback (the thesis,
// section 4.3, leaves failures open). Regula falsi with the Illinois modification: Dowell and
// Jarratt, "A modified regula falsi method for computing the root of an equation", BIT 11, 1971.
#include "refine/surface_projection.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#include <vector>

#include <glm/geometric.hpp>

namespace isomesh {
namespace {

bool finite(const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// v with the components of the axes in `axes` (bit k for axis k) zeroed.
glm::dvec3 without_axes(glm::dvec3 v, std::uint8_t axes) {
    for (int k = 0; k < 3; ++k) {
        if (axes & (1u << k)) v[k] = 0.0;
    }
    return v;
}

glm::dvec3 unit_or_zero(const glm::dvec3& v) {
    const double length = glm::length(v);
    return length > 0.0 && std::isfinite(length) ? v / length : glm::dvec3(0.0);
}

}  // namespace

SecantSearch::SecantSearch(const ProjectionRequest& request, const ProjectionSettings& settings)
    : start_(request.start),
      direction_(unit_or_zero(without_axes(request.direction, request.fixed_axes))),
      slope_(request.slope),
      radius_(settings.max_displacement * request.scale),
      tolerance_(settings.tolerance * request.scale),
      max_steps_(settings.max_secant_steps) {
    const bool usable =
        direction_ != glm::dvec3(0.0) && max_steps_ > 0 && radius_ > 0.0 && finite(start_);
    phase_ = usable ? Phase::Start : Phase::Failed;
    if (usable && !std::isnan(request.start_value)) advance(request.start_value);
}

void SecantSearch::feed(double f) {
    assert(wants_value());
    ++evaluations_;
    gradient_at_point_ = false;
    advance(f);
}

void SecantSearch::feed(const ValueGradient& vg) {
    const glm::dvec3 evaluated = next_point();
    feed(vg.value);
    // The check of the point found reads the gradient there: this one, when the search ended on
    // the very point evaluated (start + 0 * direction differs from the start in a zero's sign).
    const glm::dvec3 found_point = point();
    gradient_at_point_ = found() && std::memcmp(&evaluated, &found_point, sizeof evaluated) == 0;
    gradient_ = vg;
}

bool SecantSearch::predicts_last_value() const {
    if (steps_ == max_steps_) return true;  // the next value ends the search whatever it is
    if (std::isnan(previous_f_) || previous_t_ == t0_) return false;
    // The secant method converges superlinearly: the next residual is at most about the last one
    // shrunk by the last ratio. The search ends on it when it is within the tolerance for the
    // slope of f along the line.
    const double slope = std::abs((t0_f_ - previous_f_) / (t0_ - previous_t_));
    const double next = std::abs(t0_f_) * std::min(1.0, std::abs(t0_f_ / previous_f_));
    return next <= tolerance_ * slope;
}

void SecantSearch::advance(double f) {
    step(f);
    wants_gradient_ = phase_ == Phase::Iterating && predicts_last_value();
}

void SecantSearch::step(double f) {
    if (phase_ == Phase::Start) {
        start_value_ = t0_f_ = f;
        if (!std::isfinite(f)) {
            phase_ = Phase::Failed;
        } else if (f == 0.0) {
            phase_ = Phase::Found;
        } else {
            // The first step: Newton's with the slope estimate, or a short probe downhill (the
            // direction points roughly outward, towards f > 0).
            const double probe = f > 0.0 ? -1e-3 * radius_ : 1e-3 * radius_;
            t1_ = slope_ > 0.0 ? -f / slope_ : probe;
            t1_ = std::clamp(t1_, -0.5 * radius_, 0.5 * radius_);
            phase_ = Phase::Iterating;
        }
        return;
    }
    if (!std::isfinite(f) || std::abs(t1_) > radius_) {
        phase_ = Phase::Failed;
        return;
    }
    const double slope = f != t0_f_ && t1_ != t0_ ? std::abs((f - t0_f_) / (t1_ - t0_)) : 0.0;
    if (f == 0.0 || (slope > 0.0 && std::abs(f) <= tolerance_ * slope) || steps_ == max_steps_) {
        phase_ = Phase::Found;  // converged, or out of steps: the gradient check decides
        return;
    }
    if (!(slope > 0.0)) {
        phase_ = Phase::Failed;
        return;
    }
    const double t2 = t1_ - f * (t1_ - t0_) / (f - t0_f_);
    previous_t_ = t0_;
    previous_f_ = t0_f_;
    t0_ = t1_;
    t0_f_ = f;
    t1_ = t2;
    ++steps_;
}

namespace {

class Projector {
  public:
    Projector(Evaluator& evaluator, const ProjectionRequest& request,
              const ProjectionSettings& settings)
        : evaluator_(evaluator),
          request_(request),
          settings_(settings),
          radius_(settings.max_displacement * request.scale),
          tolerance_(settings.tolerance * request.scale) {}

    Projection run() {
        if (!(radius_ > 0.0) || !finite(request_.start)) return failed();
        SecantSearch search(request_, settings_);
        while (search.wants_value()) {
            if (search.wants_gradient())
                search.feed(evaluator_.value_gradient(search.next_point()));
            else
                search.feed(evaluator_.value(search.next_point()));
        }
        return run_after_secant(search);
    }

    // The stages after the secant search (which may have run in a batch).
    Projection run_after_secant(const SecantSearch& search) {
        evaluations_ += search.evaluations();
        if (!(radius_ > 0.0) || !finite(request_.start)) return failed();
        start_value_ = search.start_value();
        if (search.found() && check(search.point(), search.found_gradient())) return result_;
        if (newton()) return result_;
        if (bracketing()) return result_;
        return failed();
    }

  private:
    ValueGradient evaluate(const glm::dvec3& p) {
        ++evaluations_;
        return evaluator_.value_gradient(p);
    }

    double value(const glm::dvec3& p) {
        ++evaluations_;
        return evaluator_.value(p);
    }

    bool succeed(const glm::dvec3& p, const glm::dvec3& gradient, ProjectionMethod method) {
        // unit_or_zero(gradient), with the one length.
        const double norm = glm::length(gradient);
        const bool unit = norm > 0.0 && std::isfinite(norm);
        result_ = Projection{p, unit ? gradient / norm : glm::dvec3(0.0),
                             std::isfinite(norm) ? norm : 0.0, method, evaluations_};
        return true;
    }

    Projection failed() const {
        return Projection{request_.start, glm::dvec3(0.0), 0.0, ProjectionMethod::Failed,
                          evaluations_};
    }

    // Along a line at an angle to the normal the slope understates |grad f|, so the distance is
    // checked with the gradient, which also gives the normal.
    // `known`: f and grad f at p, when the search evaluated them there.
    bool check(const glm::dvec3& p, const ValueGradient* known) {
        const ValueGradient vg = known ? *known : evaluate(p);
        const double g = glm::length(without_axes(vg.gradient, request_.fixed_axes));
        if (!std::isfinite(vg.value) || !(g > 0.0) || !(std::abs(vg.value) <= tolerance_ * g))
            return false;
        return succeed(p, vg.gradient, ProjectionMethod::Secant);
    }

    bool newton() {
        glm::dvec3 p = request_.start;
        for (int step = 0; step <= settings_.max_newton_steps; ++step) {
            const ValueGradient vg = evaluate(p);
            if (step == 0 && !std::isfinite(start_value_)) start_value_ = vg.value;
            const glm::dvec3 g = without_axes(vg.gradient, request_.fixed_axes);
            const double gg = glm::dot(g, g);
            if (!std::isfinite(vg.value) || !finite(vg.gradient) || !(gg > 0.0)) return false;
            if (std::abs(vg.value) <= tolerance_ * std::sqrt(gg))
                return succeed(p, vg.gradient, ProjectionMethod::Newton);
            glm::dvec3 delta = -vg.value / gg * g;
            const double length = glm::length(delta);
            if (length > 0.5 * radius_) delta *= 0.5 * radius_ / length;  // damped far from roots
            p += delta;
            if (glm::length(p - request_.start) > radius_) return false;
        }
        return false;
    }

    // Searches start + t * direction for the sign change nearest to t = 0, then refines it.
    bool bracketing() {
        const glm::dvec3 direction =
            unit_or_zero(without_axes(request_.direction, request_.fixed_axes));
        if (direction == glm::dvec3(0.0)) return false;
        double f0 = start_value_;
        if (!std::isfinite(f0)) f0 = value(request_.start);
        const int n = settings_.bracket_samples > 0 ? settings_.bracket_samples : 1;
        double previous_t[2] = {0.0, 0.0};
        double previous_f[2] = {f0, f0};
        for (int i = 1; i <= n; ++i) {
            const double t = radius_ * std::ldexp(1.0, i - n);  // radius / 2^(n-1) ... radius
            for (int side = 0; side < 2; ++side) {
                const double signed_t = side == 0 ? t : -t;
                const double f = value(request_.start + signed_t * direction);
                if (std::isfinite(f) && std::isfinite(previous_f[side]) &&
                    (f == 0.0 || (f < 0.0) != (previous_f[side] < 0.0)) &&
                    refine(direction, previous_t[side], previous_f[side], signed_t, f))
                    return true;
                previous_t[side] = signed_t;
                previous_f[side] = f;
            }
        }
        return false;
    }

    // Illinois regula falsi on [a, b] (f(a) and f(b) of opposite signs, or f(b) = 0).
    bool refine(const glm::dvec3& direction, double a, double fa, double b, double fb) {
        const double bound = std::max(std::abs(fa), std::abs(fb));
        int last_side = 0;
        double t = b;
        double ft = fb;
        for (int iteration = 0; iteration < 100 && ft != 0.0; ++iteration) {
            if (std::abs(b - a) <= tolerance_) break;
            t = (a * fb - b * fa) / (fb - fa);
            if (!(t > std::min(a, b) && t < std::max(a, b))) t = 0.5 * (a + b);
            ft = value(request_.start + t * direction);
            if (!std::isfinite(ft)) return false;
            if ((ft < 0.0) == (fa < 0.0)) {
                a = t;
                fa = ft;
                if (last_side == -1) fb *= 0.5;
                last_side = -1;
            } else {
                b = t;
                fb = ft;
                if (last_side == 1) fa *= 0.5;
                last_side = 1;
            }
        }
        // A root has |f| near 0; a pole (1/x) has |f| growing towards the sign change.
        if (!(std::abs(ft) <= bound)) return false;
        const glm::dvec3 p = request_.start + t * direction;
        const ValueGradient vg = evaluate(p);
        return succeed(p, vg.gradient, ProjectionMethod::Bracketing);
    }

    Evaluator& evaluator_;
    const ProjectionRequest& request_;
    const ProjectionSettings& settings_;
    double radius_;
    double tolerance_;
    double start_value_ = std::nan("");
    int evaluations_ = 0;
    Projection result_;
};

/// The points of one round of batched secant searches that want the same kind of evaluation.
struct SecantRound {
    std::vector<std::size_t> active;  // indices of the searches
    std::vector<double> x, y, z, f;
    std::vector<ValueGradient> vg;

    void clear() {
        active.clear();
        x.clear();
        y.clear();
        z.clear();
    }
    void add(std::size_t i, const SecantSearch& search) {
        const glm::dvec3 p = search.next_point();
        active.push_back(i);
        x.push_back(p.x);
        y.push_back(p.y);
        z.push_back(p.z);
    }
    // Feeds each search f at its point (with the gradient: Result = ValueGradient) from one
    // batched call; a single point goes through the single-point call (cheaper, the same bits).
    template <class Result, class One, class Batch>
    void evaluate(std::span<SecantSearch> searches, std::vector<Result>& out, One one,
                  Batch batch) {
        if (active.empty()) return;
        if (active.size() == 1) {
            searches[active[0]].feed(one(glm::dvec3(x[0], y[0], z[0])));
            return;
        }
        out.resize(active.size());
        batch(PointBatch{x, y, z}, std::span<Result>(out));
        for (std::size_t k = 0; k < active.size(); ++k) searches[active[k]].feed(out[k]);
    }
};

}  // namespace

Projection project_to_surface(Evaluator& evaluator, const ProjectionRequest& request,
                              const ProjectionSettings& settings) {
    return Projector(evaluator, request, settings).run();
}

void project_to_surface(Evaluator& evaluator, std::span<const ProjectionRequest> requests,
                        std::span<Projection> out, const ProjectionSettings& settings) {
    assert(requests.size() == out.size());
    // Scratch kept per thread: the refiner projects a few points at a time, very often.
    thread_local std::vector<SecantSearch> searches;
    thread_local SecantRound values, gradients;
    searches.clear();
    for (const ProjectionRequest& r : requests) searches.emplace_back(r, settings);
    // Secant searches in lockstep: one batched evaluation per round, of the values and of the
    // values with gradients each search asks for.
    for (;;) {
        values.clear();
        gradients.clear();
        for (std::size_t i = 0; i < searches.size(); ++i) {
            if (searches[i].wants_value())
                (searches[i].wants_gradient() ? gradients : values).add(i, searches[i]);
        }
        if (values.active.empty() && gradients.active.empty()) break;
        values.evaluate(
            searches, values.f, [&](const glm::dvec3& p) { return evaluator.value(p); },
            [&](const PointBatch& b, std::span<double> out) { evaluator.values(b, out); });
        gradients.evaluate(
            searches, gradients.vg,
            [&](const glm::dvec3& p) { return evaluator.value_gradient(p); },
            [&](const PointBatch& b, std::span<ValueGradient> out) {
                evaluator.value_gradients(b, out);
            });
    }
    // Then what project_to_surface does after its own secant search.
    for (std::size_t i = 0; i < requests.size(); ++i) {
        Projector projector(evaluator, requests[i], settings);
        out[i] = projector.run_after_secant(searches[i]);
    }
}

}  // namespace isomesh
