// Edge root finding and counting (see edge_roots.h).
//
// Root finding is Newton's method on g(t) = f(a + t (b - a)) safeguarded by a bracket [ta, tb]
// on which g changes sign ("rtsafe", Press, Teukolsky, Vetterling & Flannery, Numerical Recipes,
// 3rd ed., section 9.4): a Newton step is taken when it lands inside the bracket and at least
// halves the previous step, otherwise the bracket is bisected, so convergence is quadratic near
// a simple root and never slower than bisection. The gradient evaluator gives g'(t) exactly
// (forward-mode differentiation), not by differences.
//
// Bisection keeps a sign change inside the bracket, so it converges to a root or to a point where
// f jumps across 0 (a pole such as tan at pi/2, a step such as floor). The two are told apart by
// |f|: near a root of a continuous function |f| shrinks with the bracket, near a pole it grows and
// across a jump it stays. A crossing counts as a root when |f| has dropped a thousandfold below
// its value at both ends, or when it is below both ends and the Newton step is negligible.
//
// Root counting is the interval version of the same idea (Moore 1966; Snyder 1992): on a piece
// of the edge, interval evaluation of f proves "no root" when it excludes 0, and interval
// evaluation of the derivative along the edge proves "at most one root" when it does not change
// sign and f is continuous there (a monotone function crosses 0 at most once).
#include "polygonize/edge_roots.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

#include "polygonize/lattice.h"

namespace isomesh {

glm::dvec3 EdgeSegment::at(double t) const {
    return {std::lerp(a.x, b.x, t), std::lerp(a.y, b.y, t), std::lerp(a.z, b.z, t)};
}

namespace {

constexpr int kMaxIterations = 200;
/// Newton converged when its step is below this fraction of the edge.
constexpr double kStepTolerance = 1e-14;
/// |f| must fall below this fraction of its value at the edge's ends to count as a root.
constexpr double kRootDecrease = 1e-3;

struct Sample {
    double t = 0.0;
    double value = 0.0;
    glm::dvec3 gradient{0.0};
};

EdgeRoot make_root(const EdgeSegment& edge, const Sample& s, bool found) {
    return {found, edge.at(s.t), s.value, s.gradient};
}

Sample sample(Evaluator& evaluator, const EdgeSegment& edge, double t) {
    const ValueGradient vg = evaluator.value_gradient(edge.at(t));
    return {t, vg.value, vg.gradient};
}

/// The smaller of |fa| and |fb| over the finite ones (infinity when neither is finite).
double end_magnitude(const EdgeSegment& edge) {
    double m = std::numeric_limits<double>::infinity();
    for (double f : {edge.fa, edge.fb}) {
        if (std::isfinite(f)) m = std::min(m, std::abs(f));
    }
    return m;
}

bool is_root(const EdgeSegment& edge, const Sample& best, bool newton_converged) {
    const double v = std::abs(best.value);
    if (v == 0.0) return true;
    if (!std::isfinite(v)) return false;
    const double ends = end_magnitude(edge);
    return v <= kRootDecrease * ends || (newton_converged && v < ends);
}

}  // namespace

EdgeRoot find_edge_root(Evaluator& evaluator, const EdgeSegment& edge) {
    assert(is_inside(edge.fa) != is_inside(edge.fb));
    if (edge.fa == 0.0) return make_root(edge, sample(evaluator, edge, 0.0), true);
    if (edge.fb == 0.0) return make_root(edge, sample(evaluator, edge, 1.0), true);

    const bool a_inside = is_inside(edge.fa);
    const glm::dvec3 direction = edge.b - edge.a;
    double ta = 0.0, tb = 1.0;
    // First guess: the linear interpolation of the ends (the classic Marching Cubes vertex).
    double t = 0.5;
    if (std::isfinite(edge.fa) && std::isfinite(edge.fb)) {
        const double guess = edge.fa / (edge.fa - edge.fb);
        if (guess > 0.0 && guess < 1.0) t = guess;
    }
    double previous_step = 1.0;
    Sample best{0.0, std::numeric_limits<double>::infinity(), glm::dvec3(0.0)};
    bool newton_converged = false;
    for (int iteration = 0; iteration < kMaxIterations; ++iteration) {
        const Sample s = sample(evaluator, edge, t);
        if (!(std::abs(s.value) >= std::abs(best.value))) best = s;  // NaN never replaces
        if (s.value == 0.0 || newton_converged) break;
        (is_inside(s.value) == a_inside ? ta : tb) = t;

        const double slope = glm::dot(s.gradient, direction);
        const double step = s.value / slope;
        const double newton = t - step;
        if (std::isfinite(newton) && newton > ta && newton < tb &&
            std::abs(step) <= 0.5 * previous_step) {
            previous_step = std::abs(step);
            newton_converged = previous_step <= kStepTolerance;
            t = newton;
        } else {
            const double mid = 0.5 * (ta + tb);
            // The bracket cannot shrink once its ends are adjacent doubles along the edge.
            if (edge.at(mid) == edge.at(ta) || edge.at(mid) == edge.at(tb)) break;
            previous_step = 0.5 * (tb - ta);
            t = mid;
        }
    }
    return make_root(edge, best, is_root(edge, best, newton_converged));
}

namespace {

/// Where f may jump, intervals prove little (1/x on an edge through the pole is entire however
/// short the piece): such pieces are halved into at most this many before the ends decide.
constexpr double kDiscontinuousPieces = 4.0;

/// f is monotone along the edge on the piece: its derivative keeps one sign.
bool monotone(const Interval& derivative) {
    return derivative.lo >= 0.0 || derivative.hi <= 0.0;
}

class RootCounter {
  public:
    RootCounter(Evaluator& evaluator, double min_length, int limit)
        : evaluator_(evaluator), min_length_(min_length), limit_(limit) {}

    EdgeRootCount count(const EdgeSegment& edge, const IntervalGradient* whole) {
        discontinuous_min_length_ = std::max(min_length_, edge.length() / kDiscontinuousPieces);
        visit(edge, whole);
        return result_;
    }

  private:
    void visit(const EdgeSegment& piece, const IntervalGradient* known = nullptr) {
        if (result_.roots >= limit_) return;
        const bool sign_change = is_inside(piece.fa) != is_inside(piece.fb);
        const IntervalGradient enclosure =
            known != nullptr ? *known : evaluator_.interval_gradient(piece.box());
        if (enclosure.value.value.excludes_zero()) {
            result_.false_crossing |= sign_change;
            return;
        }
        const bool continuous =
            !enclosure.value.maybe_discontinuous && !enclosure.value.maybe_undefined;
        if (continuous && monotone(enclosure.gradient[piece.axis])) {
            result_.roots += sign_change;
            return;
        }
        if (piece.length() <= (continuous ? min_length_ : discontinuous_min_length_)) {
            result_.proven = false;
            if (!sign_change) return;
            if (find_edge_root(evaluator_, piece).found) {
                ++result_.roots;
            } else {
                result_.false_crossing = true;
            }
            return;
        }
        const glm::dvec3 mid = piece.at(0.5);
        const double fm = evaluator_.value(mid);
        // Both halves' enclosures in one batch (the evaluator's narrow vector kernel costs about
        // one box), though the second is not needed once the first holds `limit` roots.
        const EdgeSegment halves[2] = {{piece.a, mid, piece.fa, fm, piece.axis},
                                       {mid, piece.b, fm, piece.fb, piece.axis}};
        const Box boxes[2] = {halves[0].box(), halves[1].box()};
        IntervalGradient enclosures[2];
        evaluator_.interval_gradients(boxes, enclosures);
        visit(halves[0], &enclosures[0]);
        visit(halves[1], &enclosures[1]);
    }

    Evaluator& evaluator_;
    double min_length_;
    double discontinuous_min_length_ = 0.0;
    int limit_;
    EdgeRootCount result_;
};

}  // namespace

EdgeRootCount count_edge_roots(Evaluator& evaluator, const EdgeSegment& edge, double min_length,
                               int limit, const IntervalGradient* whole) {
    return RootCounter(evaluator, min_length, limit).count(edge, whole);
}

}  // namespace isomesh
