// Thin triangle removal by edge collapse and edge flip (see thin_triangle_cleanup.h). Collapses
// follow Hoppe et al., "Mesh optimization" (SIGGRAPH 1993), with the link condition of Dey,
// Edelsbrunner, Guha & Nekhayev ("Topology preserving edge contraction", Publ. Inst. Math. 1999)
// guarding the topology; the vertex kept is one of the edge's ends, so it is already on the
// surface and needs no projection.
#include "polygonize/thin_triangle_cleanup.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <deque>
#include <limits>
#include <vector>

#include <glm/geometric.hpp>

namespace isomesh {

double triangle_quality(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
    const double squares = glm::dot(b - a, b - a) + glm::dot(c - b, c - b) + glm::dot(a - c, a - c);
    if (!(squares > 0.0)) return 0.0;
    return 2.0 * std::sqrt(3.0) * glm::length(glm::cross(b - a, c - a)) / squares;
}

namespace {

using Triangle = std::array<std::uint32_t, 3>;
constexpr std::uint32_t kDead = std::numeric_limits<std::uint32_t>::max();
/// A cap's largest angle exceeds 120 degrees: cos < -1/2.
constexpr double kCapCosine = -0.5;
/// Relative area below which a triangle counts as degenerate (as mesh/topology.h).
constexpr double kDegenerateArea = 1e-14;

bool is_degenerate(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
    const double longest =
        std::max({glm::dot(b - a, b - a), glm::dot(c - b, c - b), glm::dot(a - c, a - c)});
    return glm::length(glm::cross(b - a, c - a)) <= kDegenerateArea * longest;
}

class Cleanup {
  public:
    Cleanup(Mesh& mesh, std::span<const std::uint8_t> box_faces,
            const ThinTriangleSettings& settings)
        : mesh_(mesh),
          tris_(mesh.triangles),
          box_faces_(box_faces),
          settings_(settings),
          incident_(mesh.positions.size()) {
        for (std::uint32_t t = 0; t < tris_.size(); ++t) {
            for (std::uint32_t v : tris_[t]) incident_[v].push_back(t);
        }
    }

    ThinTriangleReport run() {
        for (std::uint32_t t = 0; t < tris_.size(); ++t) queue_.push_back(t);
        // Each collapse removes a vertex and each flip raises the smallest quality of its two
        // triangles, but flips can cycle in theory: bound the work.
        std::size_t budget = 10 * tris_.size() + 100;
        while (!queue_.empty() && budget-- > 0) {
            const std::uint32_t t = queue_.front();
            queue_.pop_front();
            if (tris_[t][0] != kDead && is_thin(t)) fix(t);
        }
        ThinTriangleReport report = report_;
        for (std::uint32_t t = 0; t < tris_.size(); ++t) {
            if (tris_[t][0] == kDead || !is_thin(t)) continue;
            ++report.remaining_thin;
            report.remaining_degenerate +=
                is_degenerate(p(tris_[t][0]), p(tris_[t][1]), p(tris_[t][2]));
        }
        compact();
        return report;
    }

  private:
    const glm::dvec3& p(std::uint32_t v) const { return mesh_.positions[v]; }

    glm::dvec3 vertex_normal_sum(const Triangle& tri) const {
        return mesh_.normals[tri[0]] + mesh_.normals[tri[1]] + mesh_.normals[tri[2]];
    }

    double length(std::uint32_t a, std::uint32_t b) const { return glm::distance(p(a), p(b)); }

    bool is_thin(std::uint32_t t) const {
        const Triangle& tri = tris_[t];
        for (int e = 0; e < 3; ++e) {
            if (length(tri[e], tri[(e + 1) % 3]) < settings_.min_edge_length) return true;
        }
        return triangle_quality(p(tri[0]), p(tri[1]), p(tri[2])) < settings_.min_quality;
    }

    void fix(std::uint32_t t) {
        const Triangle tri = tris_[t];
        std::array<int, 3> order{0, 1, 2};  // edges by increasing length
        std::sort(order.begin(), order.end(), [&](int a, int b) {
            return length(tri[a], tri[(a + 1) % 3]) < length(tri[b], tri[(b + 1) % 3]);
        });
        const int longest = order[2];
        const std::uint32_t apex = tri[(longest + 2) % 3];
        const glm::dvec3 da = p(tri[longest]) - p(apex), db = p(tri[(longest + 1) % 3]) - p(apex);
        const bool cap = glm::dot(da, db) < kCapCosine * glm::length(da) * glm::length(db);
        if (cap && try_flip(tri[longest], tri[(longest + 1) % 3])) return;
        for (int e : order) {
            if (try_collapse(tri[e], tri[(e + 1) % 3])) return;
        }
        if (!cap) try_flip(tri[longest], tri[(longest + 1) % 3]);
    }

    /// Alive triangles containing both a and b.
    std::vector<std::uint32_t> triangles_on_edge(std::uint32_t a, std::uint32_t b) const {
        std::vector<std::uint32_t> result;
        for (std::uint32_t t : incident_[a]) {
            const Triangle& tri = tris_[t];
            if (tri[0] == b || tri[1] == b || tri[2] == b) result.push_back(t);
        }
        return result;
    }

    std::vector<std::uint32_t> neighbours(std::uint32_t v) const {
        std::vector<std::uint32_t> result;
        for (std::uint32_t t : incident_[v]) {
            for (std::uint32_t w : tris_[t]) {
                if (w != v) result.push_back(w);
            }
        }
        std::sort(result.begin(), result.end());
        result.erase(std::unique(result.begin(), result.end()), result.end());
        return result;
    }

    bool on_boundary(std::uint32_t v) const {
        for (std::uint32_t w : neighbours(v)) {
            if (triangles_on_edge(v, w).size() == 1) return true;
        }
        return false;
    }

    static std::uint32_t third(const Triangle& tri, std::uint32_t a, std::uint32_t b) {
        for (std::uint32_t v : tri) {
            if (v != a && v != b) return v;
        }
        return kDead;
    }

    /// Whether moving v onto u keeps every other triangle of v non-degenerate and facing the same
    /// way, and the link condition holds.
    bool can_collapse(std::uint32_t v, std::uint32_t u) const {
        if ((box_faces_[v] & ~box_faces_[u]) != 0) return false;
        const std::vector<std::uint32_t> on_edge = triangles_on_edge(u, v);
        if (on_edge.empty() || on_edge.size() > 2) return false;
        std::vector<std::uint32_t> opposite;
        for (std::uint32_t t : on_edge) opposite.push_back(third(tris_[t], u, v));
        std::sort(opposite.begin(), opposite.end());
        const std::vector<std::uint32_t> nu = neighbours(u), nv = neighbours(v);
        std::vector<std::uint32_t> common;
        std::set_intersection(nu.begin(), nu.end(), nv.begin(), nv.end(),
                              std::back_inserter(common));
        if (common != opposite) return false;
        if (on_edge.size() == 2 && on_boundary(u) && on_boundary(v)) return false;
        // An opposite vertex with only the two triangles on u-v (a tetrahedron, or a fan of two on
        // the boundary) would be left with a degenerate fan.
        for (std::uint32_t o : opposite) {
            if (incident_[o].size() <= 2 || (on_edge.size() == 2 && incident_[o].size() <= 3)) {
                return false;
            }
        }
        for (std::uint32_t t : incident_[v]) {
            const Triangle& tri = tris_[t];
            if (tri[0] == u || tri[1] == u || tri[2] == u) continue;
            std::array<glm::dvec3, 3> before, after;
            for (int i = 0; i < 3; ++i) {
                before[i] = p(tri[i]);
                after[i] = tri[i] == v ? p(u) : p(tri[i]);
            }
            // A triangle may stay degenerate (several vertices at one point, where the surface
            // runs through a lattice corner, collapse one after the other) but not become so;
            // one that was degenerate must come out facing the way the surface's normals do.
            const bool was_degenerate = is_degenerate(before[0], before[1], before[2]);
            const bool is_now_degenerate = is_degenerate(after[0], after[1], after[2]);
            if (is_now_degenerate) {
                if (!was_degenerate) return false;
                continue;
            }
            const glm::dvec3 n1 = glm::cross(after[1] - after[0], after[2] - after[0]);
            const glm::dvec3 reference =
                was_degenerate ? vertex_normal_sum(tri)
                               : glm::cross(before[1] - before[0], before[2] - before[0]);
            if (!(glm::dot(reference, n1) > 0.0)) return false;
        }
        return true;
    }

    /// The smallest quality around v after moving v onto u.
    double quality_after_collapse(std::uint32_t v, std::uint32_t u) const {
        double worst = 1.0;
        for (std::uint32_t t : incident_[v]) {
            const Triangle& tri = tris_[t];
            if (tri[0] == u || tri[1] == u || tri[2] == u) continue;
            std::array<glm::dvec3, 3> q;
            for (int i = 0; i < 3; ++i) q[i] = tri[i] == v ? p(u) : p(tri[i]);
            worst = std::min(worst, triangle_quality(q[0], q[1], q[2]));
        }
        return worst;
    }

    bool try_collapse(std::uint32_t a, std::uint32_t b) {
        const bool ab = can_collapse(b, a), ba = can_collapse(a, b);
        if (!ab && !ba) return false;
        // Keep the end that leaves the better triangles; ties keep the smaller index.
        bool keep_a = ab;
        if (ab && ba) {
            const double qa = quality_after_collapse(b, a), qb = quality_after_collapse(a, b);
            keep_a = qa > qb || (qa == qb && a < b);
        }
        collapse(keep_a ? b : a, keep_a ? a : b);
        return true;
    }

    void collapse(std::uint32_t v, std::uint32_t u) {
        for (std::uint32_t t : triangles_on_edge(u, v)) kill(t);
        for (std::uint32_t t : incident_[v]) {
            for (std::uint32_t& w : tris_[t]) {
                if (w == v) w = u;
            }
            incident_[u].push_back(t);
        }
        incident_[v].clear();
        for (std::uint32_t t : incident_[u]) queue_.push_back(t);
        ++report_.collapses;
    }

    void kill(std::uint32_t t) {
        for (std::uint32_t w : tris_[t]) {
            auto& list = incident_[w];
            list.erase(std::remove(list.begin(), list.end(), t), list.end());
        }
        tris_[t] = {kDead, kDead, kDead};
    }

    /// Flips edge a-b (shared by triangles a b c and b a d) into c-d when that raises the smaller
    /// quality of the two triangles without folding them.
    bool try_flip(std::uint32_t a, std::uint32_t b) {
        const std::vector<std::uint32_t> on_edge = triangles_on_edge(a, b);
        if (on_edge.size() != 2) return false;
        // Orient: t0 has a -> b in its cycle, t1 has b -> a.
        std::uint32_t t0 = on_edge[0], t1 = on_edge[1];
        if (!has_directed_edge(tris_[t0], a, b)) std::swap(t0, t1);
        if (!has_directed_edge(tris_[t0], a, b) || !has_directed_edge(tris_[t1], b, a)) {
            return false;
        }
        const std::uint32_t c = third(tris_[t0], a, b), d = third(tris_[t1], a, b);
        if (c == d || !triangles_on_edge(c, d).empty()) return false;
        const Triangle n0{a, d, c}, n1{b, c, d};
        const double before = std::min(quality(tris_[t0]), quality(tris_[t1]));
        const double after = std::min(quality(n0), quality(n1));
        if (!(after > before)) return false;
        const glm::dvec3 old_normal = normal(tris_[t0]) + normal(tris_[t1]);
        if (!(glm::dot(normal(n0), old_normal) > 0.0 && glm::dot(normal(n1), old_normal) > 0.0)) {
            return false;
        }
        kill(t0);
        kill(t1);
        revive(t0, n0);
        revive(t1, n1);
        ++report_.flips;
        return true;
    }

    static bool has_directed_edge(const Triangle& tri, std::uint32_t a, std::uint32_t b) {
        for (int e = 0; e < 3; ++e) {
            if (tri[e] == a && tri[(e + 1) % 3] == b) return true;
        }
        return false;
    }

    double quality(const Triangle& tri) const {
        return triangle_quality(p(tri[0]), p(tri[1]), p(tri[2]));
    }
    glm::dvec3 normal(const Triangle& tri) const {
        return glm::cross(p(tri[1]) - p(tri[0]), p(tri[2]) - p(tri[0]));
    }

    void revive(std::uint32_t t, const Triangle& tri) {
        tris_[t] = tri;
        for (std::uint32_t w : tri) incident_[w].push_back(t);
        queue_.push_back(t);
    }

    /// Drops dead triangles and unused vertices, keeping the order of the rest.
    void compact() {
        std::vector<std::uint32_t> new_index(mesh_.positions.size(), kDead);
        std::uint32_t next = 0;
        for (std::uint32_t v = 0; v < new_index.size(); ++v) {
            if (incident_[v].empty()) continue;
            new_index[v] = next;
            mesh_.positions[next] = mesh_.positions[v];
            if (!mesh_.normals.empty()) mesh_.normals[next] = mesh_.normals[v];
            ++next;
        }
        mesh_.positions.resize(next);
        if (!mesh_.normals.empty()) mesh_.normals.resize(next);
        std::size_t kept = 0;
        for (const Triangle& tri : tris_) {
            if (tri[0] == kDead) continue;
            tris_[kept++] = {new_index[tri[0]], new_index[tri[1]], new_index[tri[2]]};
        }
        tris_.resize(kept);
        mesh_.neighbours.clear();
        mesh_.base_edge.clear();
    }

    Mesh& mesh_;
    std::vector<Triangle>& tris_;
    std::span<const std::uint8_t> box_faces_;
    ThinTriangleSettings settings_;
    std::vector<std::vector<std::uint32_t>> incident_;
    std::deque<std::uint32_t> queue_;
    ThinTriangleReport report_;
};

}  // namespace

ThinTriangleReport remove_thin_triangles(Mesh& mesh, std::span<const std::uint8_t> box_faces,
                                         const ThinTriangleSettings& settings) {
    assert(box_faces.size() == mesh.positions.size());
    return Cleanup(mesh, box_faces, settings).run();
}

}  // namespace isomesh
