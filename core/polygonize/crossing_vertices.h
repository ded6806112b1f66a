// Naming the vertices where the surface crosses lattice edges, so that cells of different sizes
// sharing part of a lattice line share its vertex.
//
// A crossing is named by the step of the mesh's finest cells (the deepest leaf's depth, the same
// for every cell of one mesh) on which f changes sign, found by bisection on lattice points from
// whichever cell edge contains it. Two cells whose edges overlap on a line with one sign change
// name its crossing alike, whatever their depths; the root itself is then found once, on that
// finest step.
#pragma once

#include <cstdint>
#include <span>

#include "polygonize/cell_classification.h"
#include "polygonize/edge_roots.h"
#include "polygonize/lattice.h"

namespace isomesh {

/// Lattice::edge_key of the finest step holding a crossing, with that step's depth in bits 53-57.
using CrossingKey = std::uint64_t;

/// A key for the edge of a cell at `depth` from lattice point `lower` along `axis`.
inline std::uint64_t cell_edge_key(const glm::u32vec3& lower, int axis, int depth) {
    return Lattice::edge_key(lower, axis) | std::uint64_t(depth) << 53;
}

/// The edge of a cell at `depth` from lattice point `lower` along `axis`.
struct CellEdge {
    glm::u32vec3 lower{0u};
    int axis = 0;
    int depth = 0;
};

/// The step at `finest_depth` of the cell edge on which f changes sign, by bisection on the
/// lattice points of the edge (values through `values`). Preconditions: the ends of the edge are
/// on different sides (is_inside); edge.depth <= finest_depth <= lattice.max_depth().
CrossingKey locate_crossing(CornerCache& values, const Lattice& lattice, const CellEdge& edge,
                            int finest_depth);

/// out[i] = locate_crossing(values, lattice, edges[i], finest_depth), the bisections run in
/// lockstep so that each round's midpoints are evaluated in one batch (CornerCache::prefetch,
/// bit for bit the values one at a time would give). Precondition: equal sizes.
void locate_crossings(CornerCache& values, const Lattice& lattice, std::span<const CellEdge> edges,
                      int finest_depth, std::span<CrossingKey> out);

/// The step `key` as a segment with its end values (which locate_crossing evaluated).
EdgeSegment crossing_segment(const ValueMap& values, const Lattice& lattice, CrossingKey key);

/// The linear interpolation of the crossing on its finest step: a first guess of its position.
glm::dvec3 approximate_crossing(const ValueMap& values, const Lattice& lattice, CrossingKey key);

}  // namespace isomesh
