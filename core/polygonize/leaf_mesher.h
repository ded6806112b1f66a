// Meshing one octree leaf: Marching Cubes 33 on its corners, with its interior vertex projected
// onto the surface, and its triangles patched where a neighbour is subdivided more finely so that
// the meshes of cells of different sizes meet without cracks.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "eval/evaluator.h"
#include "polygonize/ancestor_path.h"
#include "polygonize/crossing_vertices.h"
#include "polygonize/id_tables.h"
#include "polygonize/lattice.h"
#include "polygonize/leaf_index.h"

namespace isomesh {

/// A triangle corner before the mesh's vertices are numbered: a CrossingKey (a vertex on a lattice
/// edge), or kExtraVertex | i for vertex i of LeafMeshes::extra_positions (an interior or patch
/// vertex placed by the leaf mesher).
using VertexRef = std::uint64_t;
inline constexpr VertexRef kExtraVertex = std::uint64_t{1} << 63;

/// What a worker produced for its leaves.
struct LeafMeshes {
    std::vector<std::array<VertexRef, 3>> triangles;
    std::vector<glm::dvec3> extra_positions;
    std::vector<glm::dvec3> extra_normals;
    std::vector<double> extra_gradient_norms;
    /// Leaves whose faces did not match their finer neighbours: they must be split.
    std::vector<CellId> unmatched;
};

/// Everything the leaf mesher reads (shared between workers, read-only).
struct LeafMeshingInput {
    const Lattice& lattice;
    /// f at every leaf corner and at the ends of every crossing's finest step.
    const ValueMap& values;
    /// The crossing of every leaf edge whose ends are on different sides, by cell_edge_key.
    const IdMap<CrossingKey>& crossings;
    const LeafIndex& index;
};

/// Appends the triangles of `leaf` to `out`, or appends `leaf` to out.unmatched (and no
/// triangles) when a face shared with finer leaves cannot be patched.
///
/// Crack patching (Shu, Zhou & Kankanhalli, "Adaptive marching cubes", The Visual Computer 11,
/// 1995): where the leaf's face is covered by smaller leaves, the surface crosses the face along
/// the polyline the smaller leaves' triangles end on (their marching squares segments, with the
/// same face test as MC33). Each triangle edge the leaf has on that face is replaced by the
/// polyline between the same two crossings, and the triangle by a fan over the longer outline
/// (from its opposite corner, or from a new vertex projected onto the surface when several edges
/// were replaced). The match must be exact: every polyline runs from one of the leaf's crossings
/// to the one its triangle edge joins it to, and every segment on the face is used; otherwise the
/// leaf is reported unmatched (typically the surface pokes across its edge between lattice
/// points, or a face test decides differently at the finer scale) and must be split.
///
/// Vertices placed inside the leaf are projected with `evaluator`; when `path` (on the same
/// evaluator) is given, it walks to the leaf's parent before the first projection, so that the
/// projection runs on the tape specialised to it (the same results, a shorter tape: leaves in
/// octree order share the walk's ancestors).
void mesh_leaf(Evaluator& evaluator, const LeafMeshingInput& input, const CellId& leaf,
               LeafMeshes& out, AncestorPath* path = nullptr);

/// Whether a finer neighbour across some face of `leaf` is more than one level deeper where the
/// surface crosses that face (a sign change on the neighbour's face): then `leaf` must be split,
/// so that the octree is graded along the surface (2:1) and each patched polyline is short.
bool needs_grading(const LeafMeshingInput& input, const CellId& leaf);

/// MC33 needs finite values: a non-finite corner (a pole's, or NaN outside f's domain, which
/// counts as outside) gets a value of its sign larger than every finite one of the cell.
std::array<double, 8> finite_values(std::array<double, 8> values);

}  // namespace isomesh
