// Quadric-error simplification by topology-preserving half-edge collapses (see simplify.h).
//
// Each vertex carries the quadric Q = sum of area-weighted K_p = p p^T over the planes p of its
// triangles (Garland & Heckbert 1997), plus, for each boundary edge, a heavily weighted plane
// through the edge perpendicular to its triangle, so that boundaries keep their shape. Moving v
// onto u costs (Q_u + Q_v)(x_u), the squared distance of u's position to the planes of both
// neighbourhoods: collapses are made cheapest first (ties by vertex indices, so the result is
// deterministic), each re-checked when popped, since the link condition and the orientation test
// (edge_collapse.h) depend on the neighbourhood as it is then.
#include "mesh/simplify.h"

#include <array>
#include <cassert>
#include <queue>
#include <vector>

#include <glm/geometric.hpp>

#include "mesh/edge_collapse.h"

namespace isomesh {
namespace {

/// A symmetric 4x4 matrix: the quadric of a set of planes.
struct Quadric {
    std::array<double, 10> m{};  // a2 ab ac ad b2 bc bd c2 cd d2

    void add_plane(const glm::dvec3& n, double d, double weight) {
        const double v[4] = {n.x, n.y, n.z, d};
        int k = 0;
        for (int i = 0; i < 4; ++i)
            for (int j = i; j < 4; ++j) m[k++] += weight * v[i] * v[j];
    }
    void add(const Quadric& q) {
        for (int i = 0; i < 10; ++i) m[i] += q.m[i];
    }
    double error(const glm::dvec3& p) const {
        const double v[4] = {p.x, p.y, p.z, 1.0};
        double sum = 0.0;
        int k = 0;
        for (int i = 0; i < 4; ++i)
            for (int j = i; j < 4; ++j) sum += (i == j ? 1.0 : 2.0) * m[k++] * v[i] * v[j];
        return sum;
    }
};

/// Boundary planes weigh this much more than a triangle's own plane.
constexpr double kBoundaryWeight = 100.0;
/// The most triangles a collapse may leave around a vertex (see too_many_neighbours).
constexpr std::size_t kMaxValence = 16;
/// Budget checks every this many queue entries.
constexpr std::size_t kCheckInterval = 256;

struct Candidate {
    double cost;
    std::uint32_t v, u;  // move v onto u
    std::uint32_t stamp_v, stamp_u;
    bool operator>(const Candidate& o) const {
        if (cost != o.cost) return cost > o.cost;
        if (v != o.v) return v > o.v;
        return u > o.u;
    }
};

class Simplifier {
  public:
    Simplifier(Mesh& mesh, std::span<const std::uint8_t> box_faces)
        : mesh_(mesh, box_faces),
          quadrics_(mesh.positions.size()),
          stamps_(mesh.positions.size(), 0),
          blocked_(mesh.positions.size()) {}

    /// Collapses until the mesh has at most `target` triangles, no candidate is left, or the
    /// budget is exhausted (checked every kCheckInterval candidates); true when not stopped by
    /// the budget. Resumable: a later call goes on with the same queue.
    bool advance(std::size_t target, const WorkBudget& budget, SimplifyReport& report) {
        if (!prepare(budget)) {
            report.cancelled = budget.cancelled();
            return false;
        }
        while (mesh_.live_triangles() > target && !queue_.empty()) {
            if (++popped_ % kCheckInterval == 0 && budget.exhausted()) {
                report.cancelled = budget.cancelled();
                return false;
            }
            const Candidate c = queue_.top();
            queue_.pop();
            if (c.stamp_v != stamps_[c.v] || c.stamp_u != stamps_[c.u]) continue;
            if (mesh_.incident(c.v).empty()) continue;
            if (too_many_neighbours(c.v, c.u) || !mesh_.can_collapse(c.v, c.u)) {
                blocked_[c.v].push_back(c);  // until the neighbourhood changes
                continue;
            }
            collapse(c.v, c.u);
            ++report.collapses;
        }
        report.triangles = mesh_.live_triangles();
        report.reached = report.triangles <= target;
        return true;
    }

    void compact() { mesh_.compact(); }

    SimplifyReport run(std::size_t target, const WorkBudget& budget) {
        SimplifyReport report;
        if (!advance(target, budget, report)) {
            report.cancelled = true;  // cut short, by cancellation or by time
            report.triangles = mesh_.live_triangles();
        }
        mesh_.compact();
        return report;
    }

  private:
    /// The quadrics of every vertex, then every edge's candidates, a chunk between two looks at
    /// the budget; true once done.
    bool prepare(const WorkBudget& budget) {
        constexpr std::uint32_t kChunk = 16384;
        while (prepared_triangles_ < mesh_.triangle_slots()) {
            const std::uint32_t end = std::min<std::uint32_t>(
                static_cast<std::uint32_t>(mesh_.triangle_slots()), prepared_triangles_ + kChunk);
            for (; prepared_triangles_ < end; ++prepared_triangles_)
                add_triangle_planes(prepared_triangles_);
            if (budget.exhausted()) return false;
        }
        while (prepared_vertices_ < quadrics_.size()) {
            const std::uint32_t end = std::min<std::uint32_t>(
                static_cast<std::uint32_t>(quadrics_.size()), prepared_vertices_ + kChunk);
            for (; prepared_vertices_ < end; ++prepared_vertices_) push_edges(prepared_vertices_);
            if (budget.exhausted() && prepared_vertices_ < quadrics_.size()) return false;
        }
        return true;
    }

    /// Moving v onto u would give u more than kMaxValence triangles. On flat regions every
    /// collapse costs nothing, and without a cap the cheapest-first order piles them onto a few
    /// vertices: fans of slivers (100 triangles around one vertex on colonnade.vm), which are
    /// poor roots for refinement and make every later test on that vertex slow.
    bool too_many_neighbours(std::uint32_t v, std::uint32_t u) const {
        // u keeps its triangles and v's, less the two on u-v counted in both and removed.
        return mesh_.incident(u).size() + mesh_.incident(v).size() > kMaxValence + 4;
    }

    void add_triangle_planes(std::uint32_t t) {
        const auto& tri = mesh_.triangle(t);
        const glm::dvec3 a = mesh_.position(tri[0]), b = mesh_.position(tri[1]),
                         c = mesh_.position(tri[2]);
        const glm::dvec3 cross = glm::cross(b - a, c - a);
        const double twice_area = glm::length(cross);
        if (!(twice_area > 0.0)) return;
        const glm::dvec3 n = cross / twice_area;
        Quadric q;
        q.add_plane(n, -glm::dot(n, a), 0.5 * twice_area);
        for (std::uint32_t v : tri) quadrics_[v].add(q);
        // Boundary edges: a plane through the edge, perpendicular to the triangle.
        for (int e = 0; e < 3; ++e) {
            const std::uint32_t p = tri[e], r = tri[(e + 1) % 3];
            if (mesh_.triangles_on_edge(p, r).size() != 1) continue;
            const glm::dvec3 edge = mesh_.position(r) - mesh_.position(p);
            glm::dvec3 side = glm::cross(edge, n);
            const double length = glm::length(side);
            if (!(length > 0.0)) continue;
            side /= length;
            Quadric b;
            b.add_plane(side, -glm::dot(side, mesh_.position(p)),
                        kBoundaryWeight * glm::dot(edge, edge));
            quadrics_[p].add(b);
            quadrics_[r].add(b);
        }
    }

    void push_edges(std::uint32_t v) {
        for (std::uint32_t w : mesh_.neighbours(v)) {
            push(v, w);
            push(w, v);
        }
    }

    void push(std::uint32_t v, std::uint32_t u) {
        Quadric q = quadrics_[u];
        q.add(quadrics_[v]);
        queue_.push({q.error(mesh_.position(u)), v, u, stamps_[v], stamps_[u]});
    }

    void collapse(std::uint32_t v, std::uint32_t u) {
        mesh_.collapse(v, u);
        quadrics_[u].add(quadrics_[v]);
        ++stamps_[v];
        // Costs change only on u's edges (its quadric grew): those candidates are made anew. The
        // link and orientation tests change around u's neighbours too: candidates refused there
        // are tried again.
        ++stamps_[u];
        push_edges(u);
        for (std::uint32_t w : mesh_.neighbours(u)) {
            for (const Candidate& c : blocked_[w]) {
                // Stamps only grow: a stale candidate would be dropped when popped.
                if (c.stamp_v == stamps_[c.v] && c.stamp_u == stamps_[c.u]) queue_.push(c);
            }
            blocked_[w].clear();
        }
    }

    CollapseMesh mesh_;
    std::vector<Quadric> quadrics_;
    std::vector<std::uint32_t> stamps_;
    std::vector<std::vector<Candidate>> blocked_;  // refused candidates, by the vertex to move
    std::priority_queue<Candidate, std::vector<Candidate>, std::greater<>> queue_;
    std::size_t popped_ = 0;
    std::uint32_t prepared_triangles_ = 0;  // prepare()'s progress
    std::uint32_t prepared_vertices_ = 0;
};

}  // namespace

SimplifyReport simplify_to_budget(Mesh& mesh, std::span<const std::uint8_t> box_faces,
                                  std::size_t target_triangles, const WorkBudget& budget) {
    if (mesh.triangle_count() <= target_triangles) {
        SimplifyReport report;
        report.triangles = mesh.triangle_count();
        report.reached = true;
        return report;
    }
    return Simplifier(mesh, box_faces).run(target_triangles, budget);
}

class Simplification::Collapses : public Simplifier {
  public:
    using Simplifier::Simplifier;
};

Simplification::Simplification(Mesh mesh, std::vector<std::uint8_t> box_faces,
                               std::size_t target_triangles)
    : mesh_(std::make_unique<Mesh>(std::move(mesh))),
      box_faces_(std::move(box_faces)),
      target_(target_triangles) {
    if (mesh_->triangle_count() <= target_) {
        report_.triangles = mesh_->triangle_count();
        report_.reached = true;
        done_ = true;
        return;
    }
    collapses_ = std::make_unique<Collapses>(*mesh_, box_faces_);
}

Simplification::~Simplification() = default;

bool Simplification::advance(const WorkBudget& budget) {
    if (done_) return true;
    done_ = collapses_->advance(target_, budget, report_);
    if (done_) collapses_->compact();
    return done_;
}

Mesh Simplification::take() {
    assert(done_);
    collapses_.reset();
    return std::move(*mesh_);
}

}  // namespace isomesh
