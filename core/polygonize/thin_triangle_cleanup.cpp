// Thin triangle removal by edge collapse and edge flip (see thin_triangle_cleanup.h). The
// collapses are mesh/edge_collapse.h's: topology-preserving, the vertex kept is one of the edge's
// ends, so it is already on the surface and needs no projection.
#include "polygonize/thin_triangle_cleanup.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <deque>
#include <vector>

#include <glm/geometric.hpp>

#include "mesh/edge_collapse.h"

namespace isomesh {
namespace {

using Triangle = CollapseMesh::Triangle;
/// A cap's largest angle exceeds 120 degrees: cos < -1/2.
constexpr double kCapCosine = -0.5;

class Cleanup {
  public:
    Cleanup(Mesh& mesh, std::span<const std::uint8_t> box_faces,
            const ThinTriangleSettings& settings)
        : mesh_(mesh, box_faces), settings_(settings) {}

    ThinTriangleReport run() {
        for (std::uint32_t t = 0; t < mesh_.triangle_slots(); ++t) queue_.push_back(t);
        // Each collapse removes a vertex and each flip raises the smallest quality of its two
        // triangles, but flips can cycle in theory: bound the work.
        std::size_t budget = 10 * mesh_.triangle_slots() + 100;
        while (!queue_.empty() && budget-- > 0) {
            const std::uint32_t t = queue_.front();
            queue_.pop_front();
            if (mesh_.alive(t) && is_thin(t)) fix(t);
        }
        ThinTriangleReport report = report_;
        for (std::uint32_t t = 0; t < mesh_.triangle_slots(); ++t) {
            if (!mesh_.alive(t) || !is_thin(t)) continue;
            const Triangle& tri = mesh_.triangle(t);
            ++report.remaining_thin;
            report.remaining_degenerate += is_degenerate_triangle(p(tri[0]), p(tri[1]), p(tri[2]));
        }
        mesh_.compact();
        return report;
    }

  private:
    const glm::dvec3& p(std::uint32_t v) const { return mesh_.position(v); }

    double length(std::uint32_t a, std::uint32_t b) const { return glm::distance(p(a), p(b)); }

    bool is_thin(std::uint32_t t) const {
        const Triangle& tri = mesh_.triangle(t);
        for (int e = 0; e < 3; ++e) {
            if (length(tri[e], tri[(e + 1) % 3]) < settings_.min_edge_length) return true;
        }
        return triangle_quality(p(tri[0]), p(tri[1]), p(tri[2])) < settings_.min_quality;
    }

    void fix(std::uint32_t t) {
        const Triangle tri = mesh_.triangle(t);
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

    bool try_collapse(std::uint32_t a, std::uint32_t b) {
        const bool ab = mesh_.can_collapse(b, a), ba = mesh_.can_collapse(a, b);
        if (!ab && !ba) return false;
        // Keep the end that leaves the better triangles; ties keep the smaller index.
        bool keep_a = ab;
        if (ab && ba) {
            const double qa = mesh_.quality_after_collapse(b, a);
            const double qb = mesh_.quality_after_collapse(a, b);
            keep_a = qa > qb || (qa == qb && a < b);
        }
        const std::uint32_t u = keep_a ? a : b;
        mesh_.collapse(keep_a ? b : a, u);
        for (std::uint32_t t : mesh_.incident(u)) queue_.push_back(t);
        ++report_.collapses;
        return true;
    }

    /// Flips edge a-b (shared by triangles a b c and b a d) into c-d when that raises the smaller
    /// quality of the two triangles without folding them.
    bool try_flip(std::uint32_t a, std::uint32_t b) {
        const std::vector<std::uint32_t> on_edge = mesh_.triangles_on_edge(a, b);
        if (on_edge.size() != 2) return false;
        // Orient: t0 has a -> b in its cycle, t1 has b -> a.
        std::uint32_t t0 = on_edge[0], t1 = on_edge[1];
        if (!has_directed_edge(mesh_.triangle(t0), a, b)) std::swap(t0, t1);
        if (!has_directed_edge(mesh_.triangle(t0), a, b) ||
            !has_directed_edge(mesh_.triangle(t1), b, a)) {
            return false;
        }
        const std::uint32_t c = third(mesh_.triangle(t0), a, b);
        const std::uint32_t d = third(mesh_.triangle(t1), a, b);
        if (c == d || !mesh_.triangles_on_edge(c, d).empty()) return false;
        const Triangle n0{a, d, c}, n1{b, c, d};
        const double before = std::min(quality(mesh_.triangle(t0)), quality(mesh_.triangle(t1)));
        const double after = std::min(quality(n0), quality(n1));
        if (!(after > before)) return false;
        const glm::dvec3 old_normal = normal(mesh_.triangle(t0)) + normal(mesh_.triangle(t1));
        if (!(glm::dot(normal(n0), old_normal) > 0.0 && glm::dot(normal(n1), old_normal) > 0.0)) {
            return false;
        }
        mesh_.kill(t0);
        mesh_.kill(t1);
        mesh_.revive(t0, n0);
        mesh_.revive(t1, n1);
        queue_.push_back(t0);
        queue_.push_back(t1);
        ++report_.flips;
        return true;
    }

    static std::uint32_t third(const Triangle& tri, std::uint32_t a, std::uint32_t b) {
        for (std::uint32_t v : tri) {
            if (v != a && v != b) return v;
        }
        return CollapseMesh::kDead;
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

    CollapseMesh mesh_;
    ThinTriangleSettings settings_;
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
