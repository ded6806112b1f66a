// The "mid-phase simplification" of thesis 3.3.4: Marching Cubes with vertices on the surface
// leaves thin, nearly degenerate triangles (a vertex close to a lattice corner, or close to the
// middle of another triangle's edge), which refinement would waste splits on. They are removed by
// topology-preserving edge collapses and edge flips.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "mesh/edge_collapse.h"
#include "mesh/mesh.h"

namespace isomesh {

struct ThinTriangleSettings {
    /// Edges shorter than this are collapsed (a fraction of the lattice step suits).
    double min_edge_length = 0.0;
    /// Triangles of lower quality 4 sqrt(3) area / (sum of squared edge lengths) (1 for an
    /// equilateral triangle, 0 for a degenerate one) are collapsed or flipped.
    double min_quality = 0.1;
};

struct ThinTriangleReport {
    std::size_t collapses = 0;
    std::size_t flips = 0;
    /// Triangles still below the settings' thresholds (no valid operation fixed them).
    std::size_t remaining_thin = 0;
    /// Of those, triangles of zero area (|cross product| <= 1e-14 * longest edge^2).
    std::size_t remaining_degenerate = 0;
};

/// Removes thin triangles from `mesh` (positions, normals, triangles; adjacency is not kept, so
/// neighbours and base_edge are cleared) and compacts it, keeping the order of what remains.
///
/// Collapses are mesh/edge_collapse.h's: an edge u-v collapses by moving v onto u, so every
/// remaining vertex keeps its position (on the surface) and its normal, and only where the
/// topology, the boundary on the box faces (`box_faces[v]`: bit 2 * axis + side) and every
/// triangle's orientation are kept. A cap (a triangle with an angle above 120 degrees) is first
/// tried with a flip of its longest edge.
/// Deterministic: triangles are visited in index order, then those whose shape changed.
/// Preconditions: mesh manifold and consistently oriented; one normal per vertex (the surface's,
/// zero where unknown); box_faces.size() == vertex_count().
ThinTriangleReport remove_thin_triangles(Mesh& mesh, std::span<const std::uint8_t> box_faces,
                                         const ThinTriangleSettings& settings);

}  // namespace isomesh
