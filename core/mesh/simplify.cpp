// Quadric-error simplification by topology-preserving half-edge collapses (see simplify.h).
//
// Each vertex carries the quadric Q = sum of area-weighted K_p = p p^T over the planes p of its
// triangles (Garland & Heckbert 1997), plus, for each boundary edge, a heavily weighted plane
// through the edge perpendicular to its triangle, so that boundaries keep their shape. Moving v
// onto u costs (Q_u + Q_v)(x_u), the squared distance of u's position to the planes of both
// neighbourhoods: collapses are made cheapest first (ties by vertex indices, so the result is
// deterministic), each re-checked when popped, since the link condition and the orientation test
// (edge_collapse.h) depend on the neighbourhood as it is then.
//
// The queue is updated lazily (the lazy evaluation of Minoux, "Accelerated greedy algorithms
// for maximizing submodular set functions", 1978): a quadric only grows, so a candidate's cost
// only rises after it is queued; the entry is a lower bound, recomputed when it reaches the top,
// and queued again if it rose. The top entry whose cost is current is the cheapest candidate, so
// the collapses are the eager order's, while a collapse queues only the edges it creates.
#include "mesh/simplify.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>
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
    bool operator>(const Candidate& o) const {
        if (cost != o.cost) return cost > o.cost;
        if (v != o.v) return v > o.v;
        return u > o.u;
    }
};

/// A 4-ary min-heap of candidates, popping them in the order std::priority_queue with
/// std::greater would (equal ones, stale copies of one candidate, in an order that changes
/// nothing: the stale one is skipped either way). Half the levels of a binary heap and the four
/// children of a node side by side: the heap holds about ten candidates a collapse, and the
/// binary heap's sift-downs, a cache miss a level, were a third of the simplification's time.
class CandidateHeap {
  public:
    bool empty() const { return items_.empty(); }
    const Candidate& top() const { return items_.front(); }

    void push(const Candidate& c) {
        std::size_t i = items_.size();
        items_.push_back(c);
        while (i > 0) {
            const std::size_t parent = (i - 1) / kArity;
            if (!(items_[parent] > c)) break;
            items_[i] = items_[parent];
            i = parent;
        }
        items_[i] = c;
    }

    void pop() {
        const Candidate last = items_.back();
        items_.pop_back();
        const std::size_t n = items_.size();
        if (n == 0) return;
        std::size_t i = 0;
        for (std::size_t first = 1; first < n; first = kArity * i + 1) {
            std::size_t least = first;
            const std::size_t end = std::min(first + kArity, n);
            for (std::size_t k = first + 1; k < end; ++k) {
                if (items_[least] > items_[k]) least = k;
            }
            if (!(last > items_[least])) break;
            items_[i] = items_[least];
            i = least;
        }
        items_[i] = last;
    }

  private:
    static constexpr std::size_t kArity = 4;
    std::vector<Candidate> items_;
};

class Simplifier {
  public:
    Simplifier(Mesh& mesh, std::span<const std::uint8_t> box_faces)
        : mesh_(mesh, box_faces),
          quadrics_(mesh.positions.size()),
          blocked_(mesh.positions.size()) {}

    /// Collapses until the mesh has at most `target` triangles, no candidate is left, or the
    /// budget is exhausted (checked every kCheckInterval candidates); true when not stopped by
    /// the budget. Resumable: a later call goes on with the same queue (and the same quadrics:
    /// going on to a smaller target measures the error against the original surface's planes).
    bool advance(std::size_t target, const WorkBudget& budget, std::size_t& collapses) {
        if (!prepare(budget)) return false;
        while (mesh_.live_triangles() > target && !queue_.empty()) {
            if (++popped_ % kCheckInterval == 0 && budget.exhausted()) return false;
            const Candidate c = queue_.top();
            queue_.pop();
            if (mesh_.incident(c.v).empty() || mesh_.incident(c.u).empty()) continue;
            // Quadrics only grow (each a sum of squared distances), so a candidate's cost only
            // rises after it was pushed: its entry is a lower bound. The entry at the top whose
            // cost is still its cost is the cheapest candidate; one whose cost rose goes back
            // with it (lazy updates: a collapse pushes only its new edges, not every edge whose
            // cost it changed, most of which are never popped).
            const double cost = collapse_cost(c.v, c.u);
            if (cost != c.cost) {
                queue_.push({cost, c.v, c.u});
                continue;
            }
            if (too_many_neighbours(c.v, c.u) || !mesh_.can_collapse(c.v, c.u)) {
                blocked_[c.v].push_back(c);  // until the neighbourhood changes
                continue;
            }
            collapse(c.v, c.u);
            ++collapses;
        }
        return true;
    }

    std::size_t live_triangles() const { return mesh_.live_triangles(); }
    Mesh compacted() const { return mesh_.compacted(); }
    void compact() { mesh_.compact(); }

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
            for (; prepared_vertices_ < end; ++prepared_vertices_) {
                mesh_.neighbours(prepared_vertices_, around_);
                for (std::uint32_t w : around_) push(prepared_vertices_, w);
            }
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
            if (mesh_.triangles_on_edge(p, r, {}) != 1) continue;
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

    /// Moving v onto u costs (Q_u + Q_v)(x_u); NaN (a vertex at no finite point) counts as
    /// infinite, so that a popped cost always equals itself.
    double collapse_cost(std::uint32_t v, std::uint32_t u) const {
        Quadric q = quadrics_[u];
        q.add(quadrics_[v]);
        const double cost = q.error(mesh_.position(u));
        return std::isnan(cost) ? std::numeric_limits<double>::infinity() : cost;
    }

    void push(std::uint32_t v, std::uint32_t u) { queue_.push({collapse_cost(v, u), v, u}); }

    void collapse(std::uint32_t v, std::uint32_t u) {
        // v's edges to vertices not next to u become u's: new candidates. The others' costs rose
        // (u's quadric grew) and are brought up to date when popped.
        mesh_.neighbours(u, around_);
        mesh_.neighbours(v, around_v_);
        mesh_.collapse(v, u);
        quadrics_[u].add(quadrics_[v]);
        for (std::uint32_t w : around_v_) {
            if (w == u || std::binary_search(around_.begin(), around_.end(), w)) continue;
            push(u, w);
            push(w, u);
        }
        // The link and orientation tests change around u's neighbours and u: candidates refused
        // there are tried again.
        mesh_.neighbours(u, around_);
        around_.push_back(u);
        for (std::uint32_t w : around_) {
            for (const Candidate& c : blocked_[w]) {
                // One whose end collapsed away would be dropped when popped.
                if (!mesh_.incident(c.v).empty() && !mesh_.incident(c.u).empty()) queue_.push(c);
            }
            blocked_[w].clear();
        }
    }

    CollapseMesh mesh_;
    std::vector<Quadric> quadrics_;
    std::vector<std::vector<Candidate>> blocked_;   // refused candidates, by the vertex to move
    std::vector<std::uint32_t> around_, around_v_;  // neighbours, of u and of v
    CandidateHeap queue_;
    std::size_t popped_ = 0;
    std::uint32_t prepared_triangles_ = 0;  // prepare()'s progress
    std::uint32_t prepared_vertices_ = 0;
};

}  // namespace

SimplifyReport simplify_to_budget(Mesh& mesh, std::span<const std::uint8_t> box_faces,
                                  SimplifyTarget target, const WorkBudget& budget) {
    Simplification simplification(std::move(mesh), {box_faces.begin(), box_faces.end()}, target);
    const bool done = simplification.advance(budget);
    mesh = simplification.take();
    SimplifyReport report = simplification.report();
    report.cancelled = report.cancelled || !done;  // cut short, by cancellation or by time
    return report;
}

class Simplification::Collapses : public Simplifier {
  public:
    using Simplifier::Simplifier;
};

Simplification::Simplification(Mesh mesh, std::vector<std::uint8_t> box_faces,
                               SimplifyTarget target)
    : mesh_(std::make_unique<Mesh>(std::move(mesh))),
      box_faces_(std::move(box_faces)),
      target_(target) {
    if (mesh_->triangle_count() <= target_.limit) {
        report_.triangles = mesh_->triangle_count();
        report_.reached = true;
        report_.reached_preferred = report_.triangles <= target_.preferred;
        done_ = true;
        return;
    }
    collapses_ = std::make_unique<Collapses>(*mesh_, box_faces_);
}

Simplification::~Simplification() = default;

bool Simplification::advance(const WorkBudget& budget) {
    if (done_) return true;
    report_.cancelled = false;
    if (!at_limit_) {
        if (!collapses_->advance(target_.limit, budget, report_.collapses)) {
            report_.cancelled = budget.cancelled();
            return false;
        }
        report_.reached = collapses_->live_triangles() <= target_.limit;
        if (!report_.reached || target_.preferred >= target_.limit) return finish();
        at_limit_ = collapses_->compacted();
    }
    if (!collapses_->advance(target_.preferred, budget, report_.collapses)) {
        report_.cancelled = budget.cancelled();
        return false;
    }
    return finish();
}

bool Simplification::finish() {
    report_.reached_preferred = collapses_->live_triangles() <= target_.preferred;
    if (at_limit_ && !report_.reached_preferred) {
        collapses_.reset();
        *mesh_ = std::move(*at_limit_);
    } else {
        collapses_->compact();
    }
    at_limit_.reset();
    report_.triangles = mesh_->triangle_count();
    done_ = true;
    return true;
}

Mesh Simplification::take() {
    if (!done_ && at_limit_) {
        collapses_.reset();
        *mesh_ = std::move(*at_limit_);
    } else if (!done_) {
        collapses_->compact();
    }
    report_.triangles = mesh_->triangle_count();
    at_limit_.reset();
    collapses_.reset();
    return std::move(*mesh_);
}

}  // namespace isomesh
