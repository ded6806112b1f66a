// Roots of f along one axis-parallel lattice edge: counting them (to decide whether an octree
// cell's edges are crossed at most once, thesis 3.1.4) and finding the crossing that becomes a
// mesh vertex.
#pragma once

#include <span>

#include <glm/vec3.hpp>

#include "eval/evaluator.h"

namespace isomesh {

/// The segment from a to b, with fa = f(a) and fb = f(b) (NaN where f is undefined). Lattice
/// edges run along `axis` (a and b equal on the other axes, a[axis] < b[axis]); other segments
/// (find_edge_root accepts any) have axis = -1.
struct EdgeSegment {
    glm::dvec3 a{0.0};
    glm::dvec3 b{0.0};
    double fa = 0.0;
    double fb = 0.0;
    int axis = -1;

    /// Precondition (for both): axis >= 0.
    double length() const { return b[axis] - a[axis]; }
    Box box() const { return {a, b}; }
    /// The point at parameter t in [0, 1]; exactly a at 0 and b at 1, and exactly equal to a and
    /// b on the axes where they agree.
    glm::dvec3 at(double t) const;
};

/// The outcome of the search for the crossing of an edge whose ends are on different sides.
struct EdgeRoot {
    /// False when the sign change is not a root: a pole (1/x, tan), a jump (floor) or the border
    /// of f's domain, recognised by |f| not shrinking as the bracket closes in. No vertex may be
    /// placed there.
    bool found = false;
    glm::dvec3 position{0.0};
    double value = 0.0;        ///< f(position)
    glm::dvec3 gradient{0.0};  ///< grad f(position)
};

/// Safeguarded Newton iteration along the edge (Newton steps on f restricted to the edge, with
/// bisection whenever a step leaves the bracket or shrinks it too slowly: "rtsafe", Press et al.,
/// Numerical Recipes, 9.4), until |f / f'| is below 1e-14 of the edge's length or the bracket
/// cannot shrink further. A root exactly at an end is returned as that end.
/// Precondition: is_inside(fa) != is_inside(fb) (lattice.h). Any segment, not only lattice edges.
EdgeRoot find_edge_root(Evaluator& evaluator, const EdgeSegment& edge);

/// roots[i] = find_edge_root(evaluator, edges[i]), bit for bit, the searches run in lockstep a
/// few at a time so that each round's samples are evaluated in one batch
/// (Evaluator::value_gradients). Precondition: equal sizes.
void find_edge_roots(Evaluator& evaluator, std::span<const EdgeSegment> edges,
                     std::span<EdgeRoot> roots);

struct EdgeRootCount {
    /// Roots found, counted up to the caller's limit.
    int roots = 0;
    /// A sign change on the edge that is not a root (pole, jump, border of the domain).
    bool false_crossing = false;
    /// False when some piece of the edge shorter than min_length could not be proven to hold at
    /// most one root, and was counted by the sign change of its ends (bracketing).
    bool proven = true;
};

/// Counts the roots of f on the edge by recursive bisection with interval arithmetic: a piece
/// whose interval of f excludes 0 holds no root; a piece on which f is continuous and monotone
/// (the interval of its derivative along the edge does not change sign) holds one root if its
/// ends differ in sign, else none; other pieces are halved, down to min_length (or to a quarter
/// of the edge where f may be discontinuous or undefined, since intervals stay wide around a pole
/// however short the piece), below which the ends' signs decide and find_edge_root tells roots
/// from poles. Stops once `limit` roots are
/// found. Evaluates f at the midpoints it needs. Precondition: edge.axis >= 0.
/// `whole`, when given, is the enclosure of f on the whole edge (edge.box()), computed by the
/// caller (in a batch with other edges'); the count is the same.
EdgeRootCount count_edge_roots(Evaluator& evaluator, const EdgeSegment& edge, double min_length,
                               int limit = 2, const IntervalGradient* whole = nullptr);

}  // namespace isomesh
