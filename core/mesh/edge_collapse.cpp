// Topology-preserving half-edge collapses (see edge_collapse.h). Collapses follow Hoppe et al.,
// "Mesh optimization" (SIGGRAPH 1993); the link condition is Dey, Edelsbrunner, Guha & Nekhayev,
// "Topology preserving edge contraction" (Publ. Inst. Math. 1999).
#include "mesh/edge_collapse.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <iterator>

#include <glm/geometric.hpp>

namespace isomesh {
namespace {

constexpr double kDegenerateArea = 1e-14;

std::uint32_t third(const CollapseMesh::Triangle& tri, std::uint32_t a, std::uint32_t b) {
    for (std::uint32_t v : tri) {
        if (v != a && v != b) return v;
    }
    return CollapseMesh::kDead;
}

bool contains(const CollapseMesh::Triangle& tri, std::uint32_t v) {
    return tri[0] == v || tri[1] == v || tri[2] == v;
}

}  // namespace

bool is_degenerate_triangle(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
    const double longest =
        std::max({glm::dot(b - a, b - a), glm::dot(c - b, c - b), glm::dot(a - c, a - c)});
    return glm::length(glm::cross(b - a, c - a)) <= kDegenerateArea * longest;
}

double triangle_quality(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
    const double squares = glm::dot(b - a, b - a) + glm::dot(c - b, c - b) + glm::dot(a - c, a - c);
    if (!(squares > 0.0)) return 0.0;
    return 2.0 * std::sqrt(3.0) * glm::length(glm::cross(b - a, c - a)) / squares;
}

CollapseMesh::CollapseMesh(Mesh& mesh, std::span<const std::uint8_t> box_faces)
    : mesh_(mesh), box_faces_(box_faces), incident_(mesh.positions.size()) {
    assert(box_faces.size() == mesh.positions.size());
    for (std::uint32_t t = 0; t < mesh_.triangles.size(); ++t) {
        for (std::uint32_t v : mesh_.triangles[t]) incident_[v].push_back(t);
    }
    live_ = mesh_.triangles.size();
}

std::vector<std::uint32_t> CollapseMesh::triangles_on_edge(std::uint32_t a, std::uint32_t b) const {
    std::vector<std::uint32_t> result(triangles_on_edge(a, b, {}));
    triangles_on_edge(a, b, result);
    return result;
}

std::size_t CollapseMesh::triangles_on_edge(std::uint32_t a, std::uint32_t b,
                                            std::span<std::uint32_t> out) const {
    // Scan the shorter fan: after many collapses one end can have hundreds of triangles.
    if (incident_[b].size() < incident_[a].size()) std::swap(a, b);
    std::size_t count = 0;
    for (std::uint32_t t : incident_[a]) {
        if (!contains(mesh_.triangles[t], b)) continue;
        if (count < out.size()) out[count] = t;
        ++count;
    }
    return count;
}

/// The other corners of v's triangles, sorted, each as often as it appears (once for a boundary
/// edge, twice for an interior one).
void CollapseMesh::other_corners(std::uint32_t v, std::vector<std::uint32_t>& out) const {
    out.clear();
    for (std::uint32_t t : incident_[v]) {
        for (std::uint32_t w : mesh_.triangles[t]) {
            if (w != v) out.push_back(w);
        }
    }
    std::sort(out.begin(), out.end());
}

void CollapseMesh::neighbours(std::uint32_t v, std::vector<std::uint32_t>& out) const {
    other_corners(v, out);
    out.erase(std::unique(out.begin(), out.end()), out.end());
}

std::vector<std::uint32_t> CollapseMesh::neighbours(std::uint32_t v) const {
    std::vector<std::uint32_t> result;
    neighbours(v, result);
    return result;
}

namespace {

/// Whether some value appears once in `sorted_corners` (other_corners' list): an edge with one
/// triangle, on the boundary.
bool has_single(const std::vector<std::uint32_t>& sorted_corners) {
    for (std::size_t i = 0; i < sorted_corners.size();) {
        std::size_t j = i;
        while (j < sorted_corners.size() && sorted_corners[j] == sorted_corners[i]) ++j;
        if (j - i == 1) return true;
        i = j;
    }
    return false;
}

/// The next value after *it in a sorted list with repeats.
std::vector<std::uint32_t>::const_iterator next_value(
    std::vector<std::uint32_t>::const_iterator it, std::vector<std::uint32_t>::const_iterator end) {
    const std::uint32_t value = *it;
    while (it != end && *it == value) ++it;
    return it;
}

}  // namespace

bool CollapseMesh::on_boundary(std::uint32_t v) const {
    // An edge v-w is on the boundary when one triangle has it: w appears once among the other
    // corners of v's triangles (twice for an interior edge). Sorting them is O(k log k) in v's
    // valence k, where asking triangles_on_edge for each neighbour would be O(k^2).
    other_corners(v, scratch_corners_);
    return has_single(scratch_corners_);
}

bool CollapseMesh::keeps_link(std::span<const std::uint32_t> opposite) const {
    // The values common to scratch_u_ and scratch_v_ (other_corners of u and v), in order, must
    // be exactly `opposite` (sorted).
    std::size_t next = 0;
    auto a = scratch_u_.cbegin(), b = scratch_v_.cbegin();
    while (a != scratch_u_.cend() && b != scratch_v_.cend()) {
        if (*a < *b) {
            a = next_value(a, scratch_u_.cend());
        } else if (*b < *a) {
            b = next_value(b, scratch_v_.cend());
        } else {
            if (next == opposite.size() || opposite[next] != *a) return false;
            ++next;
            a = next_value(a, scratch_u_.cend());
            b = next_value(b, scratch_v_.cend());
        }
    }
    return next == opposite.size();
}

bool CollapseMesh::can_collapse(std::uint32_t v, std::uint32_t u) const {
    if ((box_faces_[v] & ~box_faces_[u]) != 0) return false;
    std::array<std::uint32_t, 2> on_edge{};
    const std::size_t sharing = triangles_on_edge(u, v, on_edge);
    if (sharing == 0 || sharing > 2) return false;
    std::array<std::uint32_t, 2> opposite{};
    for (std::size_t i = 0; i < sharing; ++i)
        opposite[i] = third(mesh_.triangles[on_edge[i]], u, v);
    if (sharing == 2 && opposite[1] < opposite[0]) std::swap(opposite[0], opposite[1]);
    const std::span<const std::uint32_t> opposites(opposite.data(), sharing);
    other_corners(u, scratch_u_);
    other_corners(v, scratch_v_);
    if (!keeps_link(opposites)) return false;
    if (sharing == 2 && has_single(scratch_u_) && has_single(scratch_v_)) return false;
    // Each opposite vertex loses its triangle on u-v. An interior one must keep three (two would
    // be a degenerate fan, two triangles folded onto each other); one on the boundary, one (an
    // ear: where the surface meets the box near a lattice corner it sits on, its three triangles
    // must be able to become two, or the zero-length edge there stays).
    for (std::uint32_t o : opposites) {
        const std::size_t has = incident_[o].size();
        if (has >= 4) continue;  // keeps 3 or more either way: no need to ask about the boundary
        const std::size_t keeps = on_boundary(o) ? 1 : 3;
        if (has < keeps + 1) return false;
    }
    return keeps_orientation(v, u);
}

bool CollapseMesh::keeps_orientation(std::uint32_t v, std::uint32_t u) const {
    for (std::uint32_t t : incident_[v]) {
        const Triangle& tri = mesh_.triangles[t];
        if (contains(tri, u)) continue;
        std::array<glm::dvec3, 3> before, after;
        for (int i = 0; i < 3; ++i) {
            before[i] = position(tri[i]);
            after[i] = tri[i] == v ? position(u) : position(tri[i]);
        }
        // A triangle may stay degenerate (several vertices at one point, where the surface runs
        // through a lattice corner, collapse one after the other) but not become so; one that
        // was degenerate must come out facing the way the surface's normals do.
        const bool was_degenerate = is_degenerate_triangle(before[0], before[1], before[2]);
        if (is_degenerate_triangle(after[0], after[1], after[2])) {
            if (!was_degenerate) return false;
            continue;
        }
        const glm::dvec3 n0 = glm::cross(before[1] - before[0], before[2] - before[0]);
        const glm::dvec3 n1 = glm::cross(after[1] - after[0], after[2] - after[0]);
        const glm::dvec3 surface_before = corner_normals(tri);
        const glm::dvec3 surface_after = corner_normals(
            {tri[0] == v ? u : tri[0], tri[1] == v ? u : tri[1], tri[2] == v ? u : tri[2]});
        if (!(glm::dot(was_degenerate ? surface_before : n0, n1) > 0.0)) return false;
        // A triangle facing the way the surface's normals at its corners do (towards f > 0)
        // keeps doing so: coarse collapses must not turn a triangle inside out against the
        // surface, even where it does not flip against its old self.
        if (glm::dot(n0, surface_before) > 0.0 && !(glm::dot(n1, surface_after) > 0.0))
            return false;
    }
    return true;
}

glm::dvec3 CollapseMesh::corner_normals(const Triangle& corners) const {
    if (mesh_.normals.empty()) return glm::dvec3(0.0);
    return mesh_.normals[corners[0]] + mesh_.normals[corners[1]] + mesh_.normals[corners[2]];
}

double CollapseMesh::quality_after_collapse(std::uint32_t v, std::uint32_t u) const {
    double worst = 1.0;
    for (std::uint32_t t : incident_[v]) {
        const Triangle& tri = mesh_.triangles[t];
        if (contains(tri, u)) continue;
        std::array<glm::dvec3, 3> q;
        for (int i = 0; i < 3; ++i) q[i] = tri[i] == v ? position(u) : position(tri[i]);
        worst = std::min(worst, triangle_quality(q[0], q[1], q[2]));
    }
    return worst;
}

void CollapseMesh::collapse(std::uint32_t v, std::uint32_t u) {
    std::array<std::uint32_t, 2> on_edge{};
    const std::size_t sharing = triangles_on_edge(u, v, on_edge);
    assert(sharing <= on_edge.size());
    for (std::size_t i = 0; i < sharing; ++i) kill(on_edge[i]);
    for (std::uint32_t t : incident_[v]) {
        for (std::uint32_t& w : mesh_.triangles[t]) {
            if (w == v) w = u;
        }
        incident_[u].push_back(t);
    }
    incident_[v].clear();
}

void CollapseMesh::kill(std::uint32_t t) {
    for (std::uint32_t w : mesh_.triangles[t]) {
        auto& list = incident_[w];
        list.erase(std::remove(list.begin(), list.end(), t), list.end());
    }
    mesh_.triangles[t] = {kDead, kDead, kDead};
    --live_;
}

void CollapseMesh::revive(std::uint32_t t, const Triangle& tri) {
    mesh_.triangles[t] = tri;
    for (std::uint32_t w : tri) incident_[w].push_back(t);
    ++live_;
}

Mesh CollapseMesh::compacted() const {
    Mesh result;
    std::vector<std::uint32_t> new_index(mesh_.positions.size(), kDead);
    for (std::uint32_t v = 0; v < new_index.size(); ++v) {
        if (incident_[v].empty()) continue;
        new_index[v] = static_cast<std::uint32_t>(result.positions.size());
        result.positions.push_back(mesh_.positions[v]);
        if (!mesh_.normals.empty()) result.normals.push_back(mesh_.normals[v]);
        if (!mesh_.gradient_norms.empty()) result.gradient_norms.push_back(mesh_.gradient_norms[v]);
    }
    result.triangles.reserve(live_);
    for (const Triangle& tri : mesh_.triangles) {
        if (tri[0] == kDead) continue;
        result.triangles.push_back({new_index[tri[0]], new_index[tri[1]], new_index[tri[2]]});
    }
    return result;
}

void CollapseMesh::compact() {
    mesh_ = compacted();
    incident_.clear();  // nothing follows
}

}  // namespace isomesh
