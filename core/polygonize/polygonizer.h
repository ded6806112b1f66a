// Phase 1 of the algorithm (thesis 3.3.2): a crude but topologically correct mesh of the surface
// f = 0 inside a box, from an octree and Marching Cubes 33, with every vertex on the surface.
// This is the mesh that progressive refinement (refine/) starts from.
#pragma once

#include <atomic>
#include <cstddef>

#include "eval/evaluator.h"
#include "mesh/mesh.h"

namespace isomesh {

/// Everything one render needs, including its cancellation flag.
struct PolygonizeSettings {
    /// The meshing box: finite, lo < hi on every axis. GeoGebra's usual view by default.
    Box box{{-5.0, -5.0, -5.0}, {5.0, 5.0, 5.0}};
    /// Every octree cell down to min_depth is examined (so no coarse cell hides a surface); below
    /// it cells are split only where the surface may be and its topology is not yet certain, down
    /// to max_depth. 0 <= min_depth <= max_depth <= 16 (kMaxOctreeDepth).
    int min_depth = 4;
    int max_depth = 9;
    /// Worker threads; 0 = one per hardware thread. The output does not depend on it.
    int threads = 0;
    /// Checked regularly: when it becomes true, polygonize returns early with an empty mesh and
    /// stats.cancelled set. May be null.
    const std::atomic<bool>* cancel = nullptr;
};

struct PolygonizeStats {
    std::size_t evaluations = 0;           ///< point evaluations of f (value, or with gradient)
    std::size_t interval_evaluations = 0;  ///< interval evaluations (with or without gradient)
    std::size_t cells = 0;                 ///< octree leaves meshed
    std::size_t unresolved_cells = 0;      ///< octree leaves accepted at max_depth unproven
    std::size_t triangles = 0;
    std::size_t vertices = 0;
    std::size_t collapses = 0;  ///< edge collapses of the thin-triangle cleanup
    std::size_t flips = 0;      ///< edge flips of the thin-triangle cleanup
    double time_ms = 0.0;
    int depth = 0;  ///< the depth of the deepest leaf
    bool cancelled = false;
};

struct PolygonizeResult {
    Mesh mesh;
    PolygonizeStats stats;
};

/// Meshes the surface f = 0 of `field` inside settings.box.
///
/// The output mesh (see mesh.h for the invariants) has its vertices on the surface (found by root
/// finding along lattice edges with the gradient, |f| / |grad f| at rounding level), unit gradient
/// normals, triangles counter-clockwise seen from f > 0, neighbours and base edges filled in, no
/// zero-area triangle, and every edge shared by two triangles except where the surface leaves the
/// box (or ends at a pole or at the border of f's domain). Sign changes of f that are not roots
/// (poles such as 1/x = 0, jumps) produce no surface. Cells are as small as the surface's
/// topology needs where it needs it (octree.h), and cells of different sizes meet without cracks
/// (leaf_mesher.h). Identical for every thread count.
///
/// Throws std::invalid_argument for an invalid box or depths; exceptions from the field's
/// evaluators are passed on.
PolygonizeResult polygonize(const Field& field, const PolygonizeSettings& settings);

}  // namespace isomesh
