// Helpers shared by the tests of phase 1 and of the pipeline: fields from expressions, and the
// checks every mesh they produce must pass.
#pragma once

#include <memory>
#include <string>
#include <string_view>

#include "eval/evaluator.h"
#include "mesh/mesh.h"
#include "mesh/topology.h"
#include "polygonize/polygonizer.h"

namespace isomesh::test {

/// The field of an expression without parameters (or of `@model.vm`); fails the test (and returns
/// null) when it does not compile.
std::shared_ptr<const Field> field_of(std::string_view expression);

/// max over the vertices of |f| / |grad f| (a first-order distance to the surface), divided by
/// the length of the box's diagonal.
double max_relative_distance(const Field& field, const Mesh& mesh, const Box& box);

/// The signed volume enclosed by a closed mesh (positive when triangles face outward).
double signed_volume(const Mesh& mesh);

/// Which base edges a mesh has: phase 1's are the longest edges (mesh.h); a refined mesh's follow
/// the bintree rule (refine/refiner.cpp) and are only checked to be edges.
enum class BaseEdges { longest, any };

/// Expects the invariants of mesh.h: manifold, consistently oriented, no degenerate triangle,
/// neighbours and base_edge filled and consistent, unit normals, every vertex within
/// 1e-9 * diagonal of the surface, and boundary edges (if any) on the faces of `box`.
void expect_valid_mesh(const Field& field, const Mesh& mesh, const Box& box,
                       BaseEdges base_edges = BaseEdges::longest);

/// Expects two meshes to be identical, bit for bit.
void expect_identical(const Mesh& a, const Mesh& b);

}  // namespace isomesh::test
