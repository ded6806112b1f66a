// Half-edge collapses that keep a mesh's topology and its vertices where they are: the one
// operation behind the thin-triangle cleanup (polygonize/thin_triangle_cleanup.h) and the
// simplification to a triangle budget (mesh/simplify.h).
//
// Collapsing v onto u removes v and the triangles on the edge u-v, and gives v's other triangles
// to u. Every remaining vertex keeps its position, so a mesh whose vertices lie on a surface
// still does. A collapse is allowed only when it keeps the topology (the link condition of Dey,
// Edelsbrunner, Guha & Nekhayev, "Topology preserving edge contraction", Publ. Inst. Math. 1999:
// the common neighbours of u and v are exactly the third vertices of the triangles on u-v; and no
// interior edge between two boundary vertices), keeps the boundary on the faces of the meshing
// box (v may not lie on a face of the box that u does not), and neither flips nor degenerates a
// triangle (one already degenerate, as where several vertices sit at one point, must come out
// facing the way the normals at its corners do).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/vec3.hpp>

#include "mesh/mesh.h"

namespace isomesh {

/// |cross product| <= 1e-14 * (longest edge)^2: collinear up to rounding (as mesh/topology.h).
bool is_degenerate_triangle(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c);

/// 4 sqrt(3) area / (sum of squared edge lengths) of the triangle a, b, c: 1 for an equilateral
/// triangle, 0 for a degenerate one.
double triangle_quality(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c);

/// A mesh being collapsed: triangles with their incidence, dead ones marked. Preconditions: mesh
/// manifold and consistently oriented; one normal per vertex (zero where unknown);
/// box_faces.size() == vertex_count() (bit 2 * axis + side for each face of the box the vertex
/// lies on).
class CollapseMesh {
  public:
    using Triangle = std::array<std::uint32_t, 3>;
    static constexpr std::uint32_t kDead = 0xffffffffu;

    CollapseMesh(Mesh& mesh, std::span<const std::uint8_t> box_faces);

    const glm::dvec3& position(std::uint32_t v) const { return mesh_.positions[v]; }
    const Triangle& triangle(std::uint32_t t) const { return mesh_.triangles[t]; }
    bool alive(std::uint32_t t) const { return mesh_.triangles[t][0] != kDead; }
    std::size_t triangle_slots() const { return mesh_.triangles.size(); }
    std::size_t live_triangles() const { return live_; }
    /// The live triangles using v.
    const std::vector<std::uint32_t>& incident(std::uint32_t v) const { return incident_[v]; }

    /// Live triangles containing both a and b.
    std::vector<std::uint32_t> triangles_on_edge(std::uint32_t a, std::uint32_t b) const;
    /// How many live triangles contain both a and b; the first out.size() of them go to `out`.
    std::size_t triangles_on_edge(std::uint32_t a, std::uint32_t b,
                                  std::span<std::uint32_t> out) const;
    /// The vertices sharing a live triangle with v, sorted.
    std::vector<std::uint32_t> neighbours(std::uint32_t v) const;
    /// The same into `out` (its storage reused: no allocation once it is large enough).
    void neighbours(std::uint32_t v, std::vector<std::uint32_t>& out) const;
    bool on_boundary(std::uint32_t v) const;

    /// Whether moving v onto u keeps the topology, the boundary on the box and every triangle's
    /// orientation (see the file comment).
    bool can_collapse(std::uint32_t v, std::uint32_t u) const;
    /// The smallest triangle_quality of v's triangles after moving it onto u.
    double quality_after_collapse(std::uint32_t v, std::uint32_t u) const;
    /// Moves v onto u. Precondition: can_collapse(v, u).
    void collapse(std::uint32_t v, std::uint32_t u);

    /// Replaces live triangle t by `tri` (an edge flip is a kill and two revives).
    void kill(std::uint32_t t);
    void revive(std::uint32_t t, const Triangle& tri);

    /// The live mesh as a Mesh of its own: dead triangles and unused vertices dropped, the order
    /// of the rest kept, no adjacency (neighbours and base edges empty).
    Mesh compacted() const;
    /// Makes the mesh compacted() in place. The last call: nothing else may follow it.
    void compact();

  private:
    void other_corners(std::uint32_t v, std::vector<std::uint32_t>& out) const;
    /// The link condition, on other_corners of u and v in scratch_u_ and scratch_v_: the common
    /// neighbours of u and v are `opposite` (sorted).
    bool keeps_link(std::span<const std::uint32_t> opposite) const;
    /// No triangle of v's flips or degenerates when v moves onto u.
    bool keeps_orientation(std::uint32_t v, std::uint32_t u) const;
    /// The sum of the normals at `corners` (zero when the mesh has none).
    glm::dvec3 corner_normals(const Triangle& corners) const;

    Mesh& mesh_;
    std::span<const std::uint8_t> box_faces_;
    std::vector<std::vector<std::uint32_t>> incident_;
    std::size_t live_ = 0;
    // Scratch space of the queries above (a CollapseMesh is used by one thread at a time): the
    // simplifier asks them about a million times on a 100,000-triangle mesh.
    mutable std::vector<std::uint32_t> scratch_corners_, scratch_u_, scratch_v_;
};

}  // namespace isomesh
