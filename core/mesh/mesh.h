// The indexed triangle mesh handed from polygonization (phase 1) to refinement (phase 2), and
// written to files by the CLI.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <vector>

#include <glm/vec3.hpp>

namespace isomesh {

inline constexpr std::uint32_t kNoNeighbour = std::numeric_limits<std::uint32_t>::max();

/// Invariants of a mesh produced by the polygonizer (checked by mesh/topology.h):
/// - triangles[t] lists vertex indices counter-clockwise seen from the side where f > 0, so the
///   geometric normal points outward (towards f > 0);
/// - edge e of triangle t joins triangles[t][e] and triangles[t][(e + 1) % 3]; neighbours[t][e]
///   is the triangle across that edge, or kNoNeighbour on the boundary of the meshing box;
/// - the mesh is manifold: every interior edge is shared by exactly two triangles;
/// - base_edge[t] is the index (0..2) of the longest edge of t (the bisection edge of phase 2);
/// - normals[v] is the unit gradient of f at positions[v], or zero where it is not defined.
/// `neighbours` and `base_edge` are empty until computed (see build_adjacency).
struct Mesh {
    std::vector<glm::dvec3> positions;
    std::vector<glm::dvec3> normals;
    /// |grad f| at each vertex where the producer knows it (phase 1 does: it found every vertex
    /// with the gradient), so that refinement need not evaluate it again; else empty.
    std::vector<double> gradient_norms;
    std::vector<std::array<std::uint32_t, 3>> triangles;
    std::vector<std::array<std::uint32_t, 3>> neighbours;
    std::vector<std::uint8_t> base_edge;

    std::size_t vertex_count() const { return positions.size(); }
    std::size_t triangle_count() const { return triangles.size(); }
};

}  // namespace isomesh
