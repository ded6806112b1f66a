// Test fixtures for the refiner: analytic fields, a phase-1-like starting mesh, and mesh checks.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>

#include "eval/evaluator.h"
#include "mesh/mesh.h"
#include "refine/mesh_delta.h"
#include "refine/refiner.h"

namespace isomesh::test {

/// f and grad f given as functions (interval queries answer "anything": the refiner never asks).
struct AnalyticFunction {
    std::function<double(const glm::dvec3&)> value;
    std::function<glm::dvec3(const glm::dvec3&)> gradient;
};

std::shared_ptr<const Field> make_analytic_field(AnalyticFunction function);
/// (x/rx)^2 + (y/ry)^2 + (z/rz)^2 - 1 scaled to match k_x x^2 + k_y y^2 + k_z z^2 - c: the field
/// k.x x^2 + k.y y^2 + k.z z^2 - c.
std::shared_ptr<const Field> make_quadric_field(const glm::dvec3& k, double c);
/// The sphere |p - center| - radius (a signed distance).
std::shared_ptr<const Field> make_sphere_field(const glm::dvec3& center, double radius);
/// The compiled expression `text` (expr/compile.h) with its parameters bound; throws on errors.
std::shared_ptr<const Field> compile_field(
    const std::string& text, const std::map<std::string, double, std::less<>>& params = {});

/// A closed starting mesh of a star-shaped surface around the origin: the cube [-1,1]^3 with
/// `n` x `n` quads per face, two triangles each, every vertex moved along its ray onto f = 0
/// (bisection along the ray). Neighbours and base edges filled by build_adjacency.
Mesh cube_sphere_mesh(const Field& field, int n);

/// The same surface cut by the plane z = 0 (the lower half kept): an open mesh whose boundary
/// vertices lie exactly on z = 0, as phase 1 leaves them on a face of its box.
Mesh half_cube_sphere_mesh(const Field& field, int n);

/// Where a mesh may have boundary edges (edges of one triangle).
enum class Boundary {
    None,        // watertight
    OnBoxFaces,  // only on faces of the meshing box (both ends share an exact coordinate)
    Anywhere,    // not checked here (compare boundary_loops with the starting mesh instead)
};

/// Empty when `mesh` is a conforming, consistently oriented manifold with symmetric neighbours
/// whose boundary edges are where `boundary` allows, else a description of the first problem.
std::string check_conforming(const Mesh& mesh, Boundary boundary = Boundary::None);

/// The number of closed loops formed by the boundary edges. A crack or a T-junction made by
/// refinement would add one.
std::size_t boundary_loops(const Mesh& mesh);

/// Vertex positions and triangles of two meshes equal exactly (same order).
bool same_mesh(const Mesh& a, const Mesh& b);

/// The refiner's mesh rebuilt from a snapshot and deltas, compared with its own view.
Mesh replay_mesh(const MeshDelta& snapshot, const std::vector<MeshDelta>& deltas,
                 std::string* error);

/// Positions and triangles of the refiner's mesh in id order, as a DeltaMesh would give them.
Mesh canonical(const RefinedMesh& refined);

}  // namespace isomesh::test
