// When is an octree cell fine enough for Marching Cubes 33 to mesh the surface inside it with the
// right topology? The test applied to each cell at or below the minimum depth.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "eval/evaluator.h"
#include "polygonize/edge_roots.h"
#include "polygonize/id_tables.h"
#include "polygonize/lattice.h"

namespace isomesh {

/// Values of f at lattice points, evaluated on first use. One per worker task (not thread-safe);
/// values already in `known` (read-only, shared between tasks) are not evaluated again.
class CornerCache {
  public:
    CornerCache(Evaluator& evaluator, const Lattice& lattice, const ValueMap* known = nullptr)
        : evaluator_(evaluator), lattice_(lattice), known_(known) {}

    double value(const glm::u32vec3& p);
    /// Evaluates, in one batch (Evaluator::values, bit for bit value()'s results), the points
    /// of `points` not known yet, so that value() finds them.
    void prefetch(std::span<const glm::u32vec3> points);
    /// The values this cache evaluated (not those of `known`).
    ValueMap& values() { return values_; }

  private:
    Evaluator& evaluator_;
    const Lattice& lattice_;
    const ValueMap* known_;
    ValueMap values_;
    std::vector<std::uint64_t> missing_;
    std::vector<double> x_, y_, z_, results_;
};

enum class CellVerdict {
    Empty,  ///< No surface to mesh in the cell.
    Leaf,   ///< Marching Cubes 33 on the cell's corners gives the surface's topology in it.
    Split,  ///< Not proven either way: subdivide.
};

/// Whether the mean value form (Moore 1966; Ratschek & Rokne) proves f has no zero on `box`:
/// f(box) lies in f(c) + sum_i G_i [-h_i, h_i] for the centre c, half-sizes h and gradient
/// enclosure G, when f is continuous on the box (not flagged). Much tighter than the natural
/// interval extension on small boxes (its overestimation shrinks quadratically): it sees that
/// x^4 - 5x^2 keeps away from 0 near x = 1.58, where the natural extension, counting x^4 and
/// 5x^2 independently, cannot.
bool mean_value_excludes_zero(const IntervalGradient& enclosure, double center_value,
                              const Box& box);

/// Whether the gradient cone condition (Plantinga & Vegter, "Isotopic approximation of implicit
/// curves and surfaces", SGP 2004) holds on a box where grad f lies in `gradient`:
/// <grad f(p), grad f(q)> > 0 for all p, q, checked as sum_i lo(G_i * G_i) > 0 with the two
/// factors of each product taken independently.
bool satisfies_gradient_cone(const Interval (&gradient)[3]);

/// Bit i set when f is monotone along axis i on a box where df/dx_i lies in gradient[i]: the
/// interval does not change sign and is not [0, 0].
unsigned monotone_axes(const Interval (&gradient)[3]);

/// Root counts of cell edges, by cell_edge_key (crossing_vertices.h; it holds the cell's depth,
/// hence max_bisections): the 8 children of a cell have 54 distinct edges among their 96, and
/// neighbouring families share the edges of their common faces, whose roots are then counted once
/// (the octree keeps one table per level: a count, count_edge_roots', is a function of the edge
/// and its depth alone).
using EdgeRootCounts = IdMap<EdgeRootCount>;

/// Where root counts are looked up and kept: `known` (read-only, shared between tasks) first,
/// then `own`, to which new counts are added. Either may be null.
struct EdgeRootTables {
    const EdgeRootCounts* known = nullptr;
    EdgeRootCounts* own = nullptr;
};

/// Decides the fate of `cell` (at or below the minimum depth), given the enclosure of f and grad f
/// over it, whose interval of f contains 0. Evaluates corners through `corners` and edges and
/// faces through `evaluator`; root counting halves an edge at most `max_bisections` times, its
/// results read from and added to `edges`. See cell_classification.cpp for the rules and why
/// they suffice.
CellVerdict classify_cell(Evaluator& evaluator, CornerCache& corners, const Lattice& lattice,
                          const CellId& cell, const IntervalGradient& enclosure, int max_bisections,
                          EdgeRootTables edges = {});

}  // namespace isomesh
