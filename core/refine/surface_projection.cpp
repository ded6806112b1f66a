// Projection onto an implicit surface: Newton's method along the gradient (the thesis, section 4.1:
// "Newton's method in the gradient direction"), made robust by a bracketing fallback (the thesis,
// section 4.3, leaves failures open). Regula falsi with the Illinois modification: Dowell and
// Jarratt, "A modified regula falsi method for computing the root of an equation", BIT 11, 1971.
#include "refine/surface_projection.h"

#include <cmath>

#include <glm/geometric.hpp>

namespace isomesh {
namespace {

bool finite(const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

glm::dvec3 without_axis(glm::dvec3 v, int axis) {
    if (axis >= 0 && axis < 3) v[axis] = 0.0;
    return v;
}

glm::dvec3 unit_or_zero(const glm::dvec3& v) {
    const double length = glm::length(v);
    return length > 0.0 && std::isfinite(length) ? v / length : glm::dvec3(0.0);
}

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
        result_ = Projection{p, unit_or_zero(gradient), method, evaluations_};
        return true;
    }

    Projection failed() const {
        return Projection{request_.start, glm::dvec3(0.0), ProjectionMethod::Failed, evaluations_};
    }

    bool newton() {
        glm::dvec3 p = request_.start;
        for (int step = 0; step <= settings_.max_newton_steps; ++step) {
            const ValueGradient vg = evaluate(p);
            if (step == 0) start_value_ = vg.value;
            const glm::dvec3 g = without_axis(vg.gradient, request_.fixed_axis);
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
            unit_or_zero(without_axis(request_.direction, request_.fixed_axis));
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

}  // namespace

Projection project_to_surface(Evaluator& evaluator, const ProjectionRequest& request,
                              const ProjectionSettings& settings) {
    return Projector(evaluator, request, settings).run();
}

}  // namespace isomesh
