// The octree of the polygonizer's first subphase (thesis 3.3.2): the cells in which Marching
// Cubes 33 will mesh the surface.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "polygonize/cell_classification.h"
#include "polygonize/lattice.h"
#include "polygonize/worker_pool.h"

namespace isomesh {

struct OctreeSettings {
    int min_depth = 4;
    int max_depth = 9;
    const std::atomic<bool>* cancel = nullptr;
};

struct OctreeLeaves {
    /// The leaves where f may have a zero, of various depths, in octree order.
    std::vector<CellId> leaves;
    /// Values of f at lattice points evaluated while building the tree (corners of cells whose
    /// edges were examined, centres of cells), to be reused rather than evaluated again.
    std::unordered_map<std::uint64_t, double> known_values;
    /// Leaves that reached max_depth without meeting the leaf conditions (meshed anyway, without
    /// the topology guarantee).
    std::size_t unresolved = 0;
    bool cancelled = false;
};

/// Builds the octree over lattice.box() and returns its leaves.
///
/// Down to min_depth every cell is examined; a cell is dropped only when interval arithmetic
/// proves f has no zero in it (the natural interval, or the mean value form). From min_depth on,
/// each cell is classified (cell_classification.h) and split until it is a leaf (Marching Cubes
/// 33 on its corners has the surface's topology) or max_depth is reached.
///
/// Work is split into subtrees handed to the pool's workers; each subtree is walked depth first
/// with Evaluator::push/pop tape simplification, and results are merged in subtree order, so the
/// output does not depend on the number of workers.
/// Preconditions: 0 <= min_depth <= max_depth == lattice.max_depth().
OctreeLeaves find_leaves(WorkerPool& workers, const Lattice& lattice,
                         const OctreeSettings& settings);

/// Replaces `leaf` by the leaves of its subtree: its children, classified like any cell below
/// min_depth (so the guarantees hold for them too) and split further if they need it. Values it
/// evaluates go to known_values; unresolved counts the new leaves accepted at max_depth.
/// Precondition: leaf.depth < lattice.max_depth().
OctreeLeaves split_leaf(Evaluator& evaluator, const Lattice& lattice,
                        const OctreeSettings& settings, const CellId& leaf,
                        const std::unordered_map<std::uint64_t, double>& known_values);

}  // namespace isomesh
