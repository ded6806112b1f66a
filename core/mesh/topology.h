// Topological checks of an indexed triangle mesh, and the adjacency the refiner needs.
#pragma once

#include <cstddef>

#include "mesh/mesh.h"

namespace isomesh {

/// Counts over the triangles of a mesh; vertices are identified by index (welding is the
/// producer's job), and only vertices used by some triangle count.
struct TopologyReport {
    std::size_t vertices = 0;           ///< distinct vertex indices used by the triangles
    std::size_t edges = 0;              ///< distinct undirected edges
    std::size_t triangles = 0;          ///< all triangles, degenerate ones included
    std::size_t components = 0;         ///< connected components (through shared vertices)
    long euler_characteristic = 0;      ///< vertices - edges + triangles
    std::size_t boundary_edges = 0;     ///< edges of exactly one triangle
    std::size_t nonmanifold_edges = 0;  ///< edges of three or more triangles
    /// Vertices whose triangles form two or more fans (surfaces touching at a point).
    std::size_t nonmanifold_vertices = 0;
    /// Triangles with a repeated vertex index, or with zero area: |cross| <= 1e-14 * (longest
    /// edge)^2, i.e. collinear up to rounding (only checked when the mesh has positions).
    std::size_t degenerate_triangles = 0;
    /// Edges of two triangles that run through it in the same direction (the two triangles
    /// disagree on which side is outside).
    std::size_t inconsistently_oriented_edges = 0;

    /// Closed: every edge has exactly two triangles.
    bool watertight() const { return boundary_edges == 0 && nonmanifold_edges == 0; }
    /// Every edge has at most two triangles and every vertex one fan of them.
    bool manifold() const { return nonmanifold_edges == 0 && nonmanifold_vertices == 0; }
    /// For a closed manifold: b0 = components and b1 = 2 * (total genus) = 2 b0 - chi.
    long first_betti_number() const {
        return 2 * static_cast<long>(components) - euler_characteristic;
    }
};

/// Throws std::invalid_argument when a triangle refers to a vertex index >= positions.size()
/// (unless positions is empty: a purely combinatorial mesh).
TopologyReport analyze_topology(const Mesh& mesh);

/// The volume enclosed by a closed mesh (divergence theorem: the sum over triangles of
/// p0 . (p1 x p2) / 6). Positive when the triangles face outwards, away from the enclosed (f < 0)
/// region, as the polygonizer's must; meaningless for an open mesh.
double signed_volume(const Mesh& mesh);

/// Fills mesh.neighbours (see mesh.h: neighbours[t][e] is across the edge from triangles[t][e]
/// to triangles[t][(e + 1) % 3], kNoNeighbour on the boundary) and mesh.base_edge (the longest
/// edge; equal lengths are ordered by the edge's (smaller, larger) vertex indices, smallest first,
/// so two triangles sharing a tied edge rank it alike). Precondition: no edge has three or more
/// triangles and every index is < positions.size(); throws std::invalid_argument otherwise.
void build_adjacency(Mesh& mesh);

}  // namespace isomesh
