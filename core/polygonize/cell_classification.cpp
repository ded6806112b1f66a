// Cell classification: the octree's stopping rule (thesis 3.1.4 "Topology guarantees", made
// checkable with interval arithmetic).
//
// A cell whose interval of f contains 0 is a leaf when one of two sufficient conditions holds:
//
// 1. The gradient cone condition of Plantinga & Vegter ("Isotopic approximation of implicit
//    curves and surfaces", SGP 2004): all gradients in the cell are less than 90 degrees apart.
//    Then f is strictly monotone along a common direction, the surface in the cell is one sheet
//    that is a graph over a plane, and a grid of such cells meshed from its corner signs is
//    isotopic to the surface. An edge may still be crossed twice near a tangency (the sheet pokes
//    across it); such a poke is removed by an isotopy and changes no topology, which is why the
//    condition does not demand single crossings. Every sub-cell inherits the condition, so
//    splitting the cell later (to match a finer neighbour, leaf_mesher.h) keeps the guarantee.
//
// 2. The thesis's condition, edges crossed at most once, strengthened so that what the corners
//    cannot see is ruled out too:
//    - f is monotone along some axis a in the cell (interval of df/da of one sign): every line
//      parallel to a meets the surface at most once, so the surface in the cell is a graph over
//      the face orthogonal to a and cannot hold a closed component or a tube;
//    - on every face, f is monotone along one of the face's two axes (or has no zero there): no
//      closed curve of the surface lies inside a face unseen by its corners, and the face cannot
//      carry the ambiguous alternating sign pattern (both edges along a monotone axis change sign
//      in the same direction);
//    - each of the 12 edges holds at most one root (edge_roots.h), proven by intervals.
//
// Cells where interval evaluation says f may be discontinuous or undefined get no gradient-based
// guarantee. Their edges are examined for roots: a cell whose sign changes are all poles or jumps
// (tan at pi/2, 1/x at 0, the border of sqrt's domain) holds no surface as far as the mesher is
// concerned (a component hidden entirely inside such a cell is not searched for); a cell mixing
// roots and poles is split so that the two separate; otherwise the thesis's single-crossing
// condition applies.
#include "polygonize/cell_classification.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>

#include "polygonize/crossing_vertices.h"
#include "polygonize/edge_roots.h"
#include "polygonize/mc33.h"

namespace isomesh {

double CornerCache::value(const glm::u32vec3& p) {
    const std::uint64_t key = Lattice::key(p);
    if (known_ != nullptr) {
        const auto known = known_->find(key);
        if (known != known_->end()) return known->second;
    }
    const auto [it, inserted] = values_.try_emplace(key, 0.0);
    if (inserted) it->second = evaluator_.value(lattice_.point(p));
    return it->second;
}

void CornerCache::prefetch(std::span<const glm::u32vec3> points) {
    missing_.clear();
    x_.clear();
    y_.clear();
    z_.clear();
    for (const glm::u32vec3& p : points) {
        const std::uint64_t key = Lattice::key(p);
        if (known_ != nullptr && known_->contains(key)) continue;
        if (!values_.try_emplace(key, 0.0).second) continue;  // known, or listed already
        missing_.push_back(key);
        const glm::dvec3 q = lattice_.point(p);
        x_.push_back(q.x);
        y_.push_back(q.y);
        z_.push_back(q.z);
    }
    if (missing_.empty()) return;
    results_.resize(missing_.size());
    evaluator_.values({x_, y_, z_}, results_);
    for (std::size_t i = 0; i < missing_.size(); ++i) values_[missing_[i]] = results_[i];
}

namespace {

/// Lower bound of the product of two independent copies of x.
double product_lower_bound(const Interval& x) {
    if (x.lo < 0.0 && x.hi > 0.0) return x.lo * x.hi;
    return std::min(x.lo * x.lo, x.hi * x.hi);
}

bool keeps_sign(const Interval& x) {
    return (x.lo >= 0.0 && x.hi > 0.0) || (x.hi <= 0.0 && x.lo < 0.0);
}

struct EdgeSurvey {
    int roots = 0;      // total over the edges
    int max_roots = 0;  // on the worst edge (counted up to 2)
    bool false_crossing = false;
};

/// Counts the roots on the cell's 12 edges. `monotone`: the axes along which f is continuous and
/// monotone on the whole cell (monotone_axes of its enclosure, or 0): an edge along one of them
/// holds one root if its ends differ in sign, else none, as its own enclosure (inside the
/// cell's) would prove, so it needs no evaluation.
EdgeSurvey survey_edges(Evaluator& evaluator, CornerCache& corners, const Lattice& lattice,
                        const CellId& cell, int max_bisections, EdgeRootTables tables,
                        unsigned monotone) {
    std::array<EdgeSegment, 12> edges;
    std::array<std::uint64_t, 12> keys;
    std::array<std::optional<EdgeRootCount>, 12> counted;
    std::array<Box, 12> boxes;
    std::array<int, 12> slot;
    int fresh = 0;
    for (int e = 0; e < 12; ++e) {
        const auto [c0, c1] = kEdgeCorners[e];
        const glm::u32vec3 p0 = lattice.corner(cell, c0), p1 = lattice.corner(cell, c1);
        edges[e] = {lattice.point(p0), lattice.point(p1), corners.value(p0), corners.value(p1),
                    e / 4};
        keys[e] = cell_edge_key(p0, e / 4, cell.depth);
        if ((monotone >> (e / 4)) & 1u) {
            counted[e] = EdgeRootCount{is_inside(edges[e].fa) != is_inside(edges[e].fb)};
            continue;
        }
        for (const EdgeRootCounts* table :
             {tables.known, static_cast<const EdgeRootCounts*>(tables.own)}) {
            if (table == nullptr || counted[e]) continue;
            const auto it = table->find(keys[e]);
            if (it != table->end()) counted[e] = it->second;
        }
        if (!counted[e]) {
            slot[e] = fresh;
            boxes[fresh++] = edges[e].box();
        }
    }
    // The whole edges' enclosures in one batch (the evaluator's vector kernels): most edges are
    // decided by them alone.
    std::array<IntervalGradient, 12> wholes;
    evaluator.interval_gradients(std::span(boxes).first(fresh), std::span(wholes).first(fresh));
    EdgeSurvey survey;
    for (int e = 0; e < 12; ++e) {
        EdgeRootCount count;
        if (counted[e]) {
            count = *counted[e];
        } else {
            const double min_length = std::ldexp(edges[e].length(), -max_bisections);
            count = count_edge_roots(evaluator, edges[e], min_length, 2, &wholes[slot[e]]);
            if (tables.own != nullptr) tables.own->emplace(keys[e], count);
        }
        survey.roots += count.roots;
        survey.max_roots = std::max(survey.max_roots, count.roots);
        survey.false_crossing |= count.false_crossing;
        if (survey.max_roots >= 2) break;
    }
    return survey;
}

/// Whether no closed curve of the surface can hide inside either face of `box` orthogonal to
/// `axis`: f has no zero on the face, or is monotone along one of the face's axes.
bool faces_are_simple(Evaluator& evaluator, const Box& box, int axis) {
    Box faces[2] = {box, box};
    faces[0].hi[axis] = box.lo[axis];
    faces[1].lo[axis] = box.hi[axis];
    IntervalGradient enclosures[2];
    evaluator.interval_gradients(faces, enclosures);  // one batch (about the cost of one face)
    for (const IntervalGradient& enclosure : enclosures) {
        if (enclosure.value.value.excludes_zero()) continue;
        const unsigned in_face = monotone_axes(enclosure.gradient) & ~(1u << axis);
        if (in_face == 0) return false;
    }
    return true;
}

CellVerdict classify_discontinuous(const EdgeSurvey& survey) {
    if (survey.roots == 0) return CellVerdict::Empty;
    if (survey.false_crossing || survey.max_roots >= 2) return CellVerdict::Split;
    return CellVerdict::Leaf;
}

}  // namespace

bool mean_value_excludes_zero(const IntervalGradient& enclosure, double center_value,
                              const Box& box) {
    if (enclosure.value.maybe_discontinuous || enclosure.value.maybe_undefined) return false;
    double reach = 0.0;
    for (int axis = 0; axis < 3; ++axis) {
        const Interval& g = enclosure.gradient[axis];
        reach += std::max(std::abs(g.lo), std::abs(g.hi)) * 0.5 * (box.hi[axis] - box.lo[axis]);
    }
    // The sum above is rounded to nearest: a relative margin far above its error keeps it sound.
    constexpr double kMargin = 1e-9;
    return std::isfinite(reach) && std::abs(center_value) > reach * (1.0 + kMargin);
}

bool satisfies_gradient_cone(const Interval (&gradient)[3]) {
    double sum = 0.0;
    for (const Interval& g : gradient) sum += product_lower_bound(g);
    return sum > 0.0;
}

unsigned monotone_axes(const Interval (&gradient)[3]) {
    unsigned axes = 0;
    for (int axis = 0; axis < 3; ++axis) {
        if (keeps_sign(gradient[axis])) axes |= 1u << axis;
    }
    return axes;
}

CellVerdict classify_cell(Evaluator& evaluator, CornerCache& corners, const Lattice& lattice,
                          const CellId& cell, const IntervalGradient& enclosure, int max_bisections,
                          EdgeRootTables edges) {
    const bool continuous =
        !enclosure.value.maybe_discontinuous && !enclosure.value.maybe_undefined;
    if (!continuous) {
        return classify_discontinuous(
            survey_edges(evaluator, corners, lattice, cell, max_bisections, edges, 0));
    }
    if (satisfies_gradient_cone(enclosure.gradient)) return CellVerdict::Leaf;

    const unsigned monotone = monotone_axes(enclosure.gradient);
    if (monotone == 0) return CellVerdict::Split;
    const Box box = lattice.cell_box(cell);
    for (int axis = 0; axis < 3; ++axis) {
        // The cell's own monotone axes other than `axis` already cover the faces orthogonal to it.
        if ((monotone & ~(1u << axis)) != 0) continue;
        if (!faces_are_simple(evaluator, box, axis)) return CellVerdict::Split;
    }
    const EdgeSurvey survey =
        survey_edges(evaluator, corners, lattice, cell, max_bisections, edges, monotone);
    return survey.max_roots <= 1 ? CellVerdict::Leaf : CellVerdict::Split;
}

}  // namespace isomesh
