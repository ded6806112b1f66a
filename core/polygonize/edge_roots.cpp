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
#include <array>
#include <cassert>
#include <cmath>
#include <limits>
#include <optional>

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

namespace {

/// One edge's safeguarded Newton iteration, a sample at a time, so that several edges can run in
/// lockstep (find_edge_roots): next() is where f is wanted, take() what it is there.
class RootSearch {
  public:
    explicit RootSearch(const EdgeSegment& edge) : edge_(&edge) {
        assert(is_inside(edge.fa) != is_inside(edge.fb));
        if (edge.fa == 0.0 || edge.fb == 0.0) {
            // A root exactly at an end: that end, with f and its gradient there.
            at_end_ = true;
            t_ = edge.fa == 0.0 ? 0.0 : 1.0;
            return;
        }
        a_inside_ = is_inside(edge.fa);
        // First guess: the linear interpolation of the ends (the classic Marching Cubes vertex).
        if (std::isfinite(edge.fa) && std::isfinite(edge.fb)) {
            const double guess = edge.fa / (edge.fa - edge.fb);
            if (guess > 0.0 && guess < 1.0) t_ = guess;
        }
    }

    bool done() const { return done_; }
    glm::dvec3 next() const { return edge_->at(t_); }

    void take(const ValueGradient& vg) {
        const Sample s{t_, vg.value, vg.gradient};
        if (at_end_) {
            best_ = s;
            done_ = true;
            return;
        }
        if (!(std::abs(s.value) >= std::abs(best_.value))) best_ = s;  // NaN never replaces
        if (s.value == 0.0 || newton_converged_) {
            done_ = true;
            return;
        }
        (is_inside(s.value) == a_inside_ ? ta_ : tb_) = t_;

        const double slope = glm::dot(s.gradient, edge_->b - edge_->a);
        const double step = s.value / slope;
        const double newton = t_ - step;
        if (std::isfinite(newton) && newton > ta_ && newton < tb_ &&
            std::abs(step) <= 0.5 * previous_step_) {
            previous_step_ = std::abs(step);
            newton_converged_ = previous_step_ <= kStepTolerance;
            t_ = newton;
        } else {
            const double mid = 0.5 * (ta_ + tb_);
            // The bracket cannot shrink once its ends are adjacent doubles along the edge.
            if (edge_->at(mid) == edge_->at(ta_) || edge_->at(mid) == edge_->at(tb_)) {
                done_ = true;
                return;
            }
            previous_step_ = 0.5 * (tb_ - ta_);
            t_ = mid;
        }
        done_ = ++iteration_ >= kMaxIterations;
    }

    EdgeRoot root() const {
        return make_root(*edge_, best_, at_end_ || is_root(*edge_, best_, newton_converged_));
    }

  private:
    const EdgeSegment* edge_;
    bool at_end_ = false;
    bool a_inside_ = false;
    double ta_ = 0.0, tb_ = 1.0, t_ = 0.5;
    double previous_step_ = 1.0;
    int iteration_ = 0;
    Sample best_{0.0, std::numeric_limits<double>::infinity(), glm::dvec3(0.0)};
    bool newton_converged_ = false;
    bool done_ = false;
};

/// Searches run in lockstep: each round evaluates f and its gradient at the next point of every
/// search still going, in one batch.
constexpr std::size_t kLockstep = 8;

}  // namespace

void find_edge_roots(Evaluator& evaluator, std::span<const EdgeSegment> edges,
                     std::span<EdgeRoot> roots) {
    assert(edges.size() == roots.size());
    for (std::size_t begin = 0; begin < edges.size(); begin += kLockstep) {
        const std::size_t n = std::min(kLockstep, edges.size() - begin);
        std::array<std::optional<RootSearch>, kLockstep> searches;
        for (std::size_t i = 0; i < n; ++i) searches[i].emplace(edges[begin + i]);
        std::array<std::size_t, kLockstep> going;
        std::array<double, kLockstep> x, y, z;
        std::array<ValueGradient, kLockstep> samples;
        for (;;) {
            std::size_t m = 0;
            for (std::size_t i = 0; i < n; ++i) {
                if (searches[i]->done()) continue;
                const glm::dvec3 p = searches[i]->next();
                going[m] = i;
                x[m] = p.x;
                y[m] = p.y;
                z[m] = p.z;
                ++m;
            }
            if (m == 0) break;
            evaluator.value_gradients(
                {std::span(x).first(m), std::span(y).first(m), std::span(z).first(m)},
                std::span(samples).first(m));
            for (std::size_t k = 0; k < m; ++k) searches[going[k]]->take(samples[k]);
        }
        for (std::size_t i = 0; i < n; ++i) roots[begin + i] = searches[i]->root();
    }
}

EdgeRoot find_edge_root(Evaluator& evaluator, const EdgeSegment& edge) {
    EdgeRoot root;
    find_edge_roots(evaluator, {&edge, 1}, {&root, 1});
    return root;
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
