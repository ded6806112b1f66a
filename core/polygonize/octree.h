// The octree of the polygonizer's first subphase (thesis 3.3.2): the cells, all of one depth, in
// which Marching Cubes 33 will mesh the surface.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "polygonize/lattice.h"
#include "polygonize/worker_pool.h"

namespace isomesh {

struct OctreeSettings {
    int min_depth = 4;
    int max_depth = 9;
    const std::atomic<bool>* cancel = nullptr;
};

struct SurfaceCells {
    /// The common depth of the cells: the deepest depth any cell needed.
    int depth = 0;
    /// Cells at `depth` whose interval of f contains 0, in a deterministic order (octree order).
    std::vector<CellId> cells;
    /// Values of f at lattice points already evaluated while building the tree (corners of
    /// cells whose edges were examined), to be reused rather than evaluated again.
    std::unordered_map<std::uint64_t, double> known_values;
    /// Cells that reached max_depth without meeting the leaf conditions (meshed anyway, without
    /// the topology guarantee).
    std::size_t unresolved = 0;
    bool cancelled = false;
};

/// Builds the octree over lattice.box() and returns the cells to mesh.
///
/// Down to min_depth every cell is examined; a cell is dropped only when interval arithmetic
/// proves f has no zero in it. From min_depth on, each cell is classified (cell_classification.h)
/// and split until it is a leaf or max_depth is reached. Then the cracks that cells of different
/// depths would leave between their meshes are avoided the thesis's way: every leaf is refined to
/// the deepest leaf's depth D (dropping sub-cells without a zero), so the output is Marching
/// Cubes 33 on the cells of one uniform lattice, watertight by construction. A leaf's guarantee
/// is inherited by its sub-cells (see cell_classification.cpp). The cost is that one small
/// feature refines the whole surface.
///
/// Work is split into subtrees handed to the pool's workers; each subtree is walked depth first
/// with Evaluator::push/pop tape simplification, and results are merged in subtree order, so the
/// output does not depend on the number of workers.
/// Preconditions: 0 <= min_depth <= max_depth == lattice.max_depth().
SurfaceCells find_surface_cells(WorkerPool& workers, const Lattice& lattice,
                                const OctreeSettings& settings);

}  // namespace isomesh
