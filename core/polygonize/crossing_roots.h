// Step 5 of phase 1 (frontier_mesher.cpp): the surface's vertices, one root per lattice-edge
// crossing the leaves' triangles use, found on its finest step by safeguarded Newton iteration with
// the gradient (edge_roots.h), group by group with the evaluator specialised to each group's cell;
// then the mesh assembled from them and the leaves' own vertices.
#pragma once

#include <cstddef>
#include <vector>

#include "mesh/mesh.h"
#include "polygonize/crossing_vertices.h"
#include "polygonize/edge_roots.h"
#include "polygonize/evaluator_pool.h"
#include "polygonize/id_tables.h"
#include "polygonize/lattice.h"
#include "polygonize/leaf_mesher.h"
#include "work/work_budget.h"

namespace isomesh {

/// The surface's vertices on lattice edges: roots on the finest steps of the crossings used.
struct CrossingRoots {
    std::vector<CrossingKey> keys;  // sorted
    std::vector<EdgeRoot> roots;
    /// Indices of keys by group cell (root_group), in octree order: the order roots are found in.
    std::vector<std::size_t> order;
    std::vector<CellId> groups;  // of keys
};

/// The crossings the leaves' triangles use, their roots not found yet, ordered by group.
CrossingRoots crossings_used(const std::vector<LeafMeshes>& parts, const Lattice& lattice,
                             int finest_depth);

/// Finds the roots of crossings order[begin, end) of `crossings`, group by group, the groups in
/// octree order, on the pool's workers; the budget's cancellation is checked between batches.
void find_roots(EvaluatorPool& workers, const Lattice& lattice, const ValueMap& values,
                CrossingRoots& crossings, std::size_t begin, std::size_t end,
                const WorkBudget& budget);

/// The mesh: a vertex per crossing that is a root, then the leaves' own vertices; triangles
/// touching a crossing that is not a root (a pole, a jump) are left out.
Mesh assemble_mesh(const CrossingRoots& crossings, const std::vector<LeafMeshes>& parts);

}  // namespace isomesh
