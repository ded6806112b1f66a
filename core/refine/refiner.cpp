// Progressive refinement: ROAM's split and merge queues on the dual graph of an arbitrary
// triangle mesh.
//
// - Duchaineau, Wolinsky, Sigeti, Miller, Aldrich, Mineev-Weinstein, "ROAMing terrain: Real-time
//   Optimally Adapting Meshes", IEEE Visualization 1997: forced splits, merge of diamonds, the
//   dual-queue optimisation.
// - The thesis behind isomesh (chapter 3.2.3 and 3.3.3, Algorithm 2): ROAM on the dual graph of a
//   Marching Cubes mesh, bisection at the projected base midpoint, epsilon_4, constraints, the
//   multi-rooted tree for merges, versions for dynamic data.
// - Mitchell, "A comparison of adaptive refinement techniques for elliptic problems", ACM TOMS
//   15(4), 1989 (newest vertex bisection), and Karkulik, Pavlicek, Praetorius, "On 2D newest vertex
//   bisection: optimality of mesh-closure and H1-stability of L2-projection", Constructive
//   Approximation 38, 2013: with any initial choice of base edges, recursive bisection terminates.
//
// The mesh is a forest. Every phase-1 triangle is a root; a split record owns the one vertex it
// created and the two or four children that replaced its one or two parents (a "diamond" of two
// triangles sharing their base edge, or one triangle whose base edge is on the boundary). Leaves
// are the visible triangles. A record can be merged when all its children are leaves.
//
// Bisection of triangle (a, b, c) with base edge a-b at vertex m gives (a, m, c) and (m, b, c);
// each child's base edge is the side it inherits from the parent (c-a and b-c), the edge opposite
// the newest vertex m. So when T's base neighbour N has another base edge, splitting N once leaves
// a child of N whose base edge is T's: each forced split in a chain adds exactly 2 triangles, and
// the cost of a split is known before it is made.
#include "refine/refiner.h"

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "mesh/topology.h"

namespace isomesh {
namespace {

constexpr std::uint32_t kNone = kNoNeighbour;
static_assert(kNoNeighbour == PriorityQueue::kNone);

enum class TriangleState : std::uint8_t { Leaf, Split, Free };

struct Vertex {
    std::uint32_t id = 0;
    glm::dvec3 position{0.0};
    glm::dvec3 normal{0.0};
    double gradient_norm = 0.0;  // |grad f| at position; 0 when unknown
    double scale = 0.0;  // the length of the edge it bisected (phase-1: shortest incident edge)
    std::uint64_t version = 0;
    std::int8_t fixed_axis = -1;  // on a face of the meshing box: the coordinate that stays
    bool on_surface = true;
    bool alive = false;
};

struct Triangle {
    std::uint32_t id = 0;
    std::array<std::uint32_t, 3> v{};   // vertex slots, counter-clockwise
    std::array<std::uint32_t, 3> nb{};  // triangle slot across edge v[e]-v[e+1], or kNone
    std::uint8_t base = 0;
    TriangleState state = TriangleState::Free;
    std::uint32_t parent = kNone;  // the split record that created it; kNone for roots
    std::uint32_t split = kNone;   // the split record that replaced it (state Split)
    // The base midpoint projected onto the surface: the vertex a split would create.
    glm::dvec3 candidate{0.0};
    glm::dvec3 candidate_normal{0.0};
    double candidate_gradient_norm = 0.0;
    bool candidate_on_surface = false;
    std::uint64_t candidate_version = 0;
    double error = 0.0;
    std::uint64_t error_version = 0;
};

struct SplitRecord {
    std::uint32_t vertex = kNone;
    std::array<std::uint32_t, 2> parents{kNone, kNone};  // parents[1] = kNone on the boundary
    std::array<std::uint32_t, 4> children{kNone, kNone, kNone, kNone};  // 0,1 of parents[0]
    std::uint32_t split_children = 0;  // children that are not leaves
    bool alive = false;
};

/// Slots with a free list; freed slots are reused last-in first-out (deterministically).
template <typename T>
class Pool {
  public:
    std::uint32_t allocate() {
        if (!free_.empty()) {
            const std::uint32_t slot = free_.back();
            free_.pop_back();
            items_[slot] = T{};
            return slot;
        }
        items_.emplace_back();
        return static_cast<std::uint32_t>(items_.size() - 1);
    }
    void release(std::uint32_t slot) { free_.push_back(slot); }
    void clear() {
        items_.clear();
        free_.clear();
    }
    T& operator[](std::uint32_t slot) { return items_[slot]; }
    const T& operator[](std::uint32_t slot) const { return items_[slot]; }
    std::uint32_t size() const { return static_cast<std::uint32_t>(items_.size()); }

  private:
    std::vector<T> items_;
    std::vector<std::uint32_t> free_;
};

/// Neumaier's compensated sum, so that adding and removing many errors does not drift.
class CompensatedSum {
  public:
    void add(double x) {
        const double t = sum_ + x;
        if (std::abs(sum_) >= std::abs(x))
            compensation_ += (sum_ - t) + x;
        else
            compensation_ += (x - t) + sum_;
        sum_ = t;
    }
    double value() const { return sum_ + compensation_; }
    void clear() { sum_ = compensation_ = 0.0; }

  private:
    double sum_ = 0.0;
    double compensation_ = 0.0;
};

std::unique_ptr<PriorityQueue> make_queue(QueueKind kind, QueueOrder order,
                                          const BucketQueueSettings& buckets) {
    if (kind == QueueKind::Heap) return std::make_unique<HeapQueue>(order);
    return std::make_unique<BucketQueue>(order, buckets);
}

bool finite(const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

glm::dvec3 unit_or_zero(const glm::dvec3& v) {
    const double length = glm::length(v);
    return length > 0.0 && std::isfinite(length) ? v / length : glm::dvec3(0.0);
}

/// The axis of the face of the meshing box that a boundary edge a-b lies on, or -1: phase 1 puts
/// such edges exactly on the box, which the mesh's bounding box `bounds` touches. (A plane such
/// as x = 0 has every vertex at x = 0: that axis, flat in `bounds`, is not a face.)
std::int8_t face_axis(const glm::dvec3& a, const glm::dvec3& b, const Box& bounds) {
    for (int k = 0; k < 3; ++k)
        if (a[k] == b[k] && bounds.lo[k] < bounds.hi[k] &&
            (a[k] == bounds.lo[k] || a[k] == bounds.hi[k]))
            return static_cast<std::int8_t>(k);
    return -1;
}

bool same_topology(const TopologyReport& a, const TopologyReport& b) {
    return a.components == b.components && a.euler_characteristic == b.euler_characteristic &&
           (a.boundary_edges == 0) == (b.boundary_edges == 0);
}

/// The forced splits one split needs: chain[0] is the triangle asked for, chain[i + 1] the base
/// neighbour of chain[i] (whose base edge differs); the last one is bisected with `partner` (its
/// base neighbour sharing its base edge) or alone on the boundary (partner kNone).
struct SplitPlan {
    std::vector<std::uint32_t> chain;
    std::uint32_t partner = kNone;
    std::size_t added_triangles = 0;
    std::size_t bisections() const { return chain.size(); }
};

}  // namespace

std::string validate_refinable(const Mesh& mesh) {
    const std::size_t n = mesh.positions.size();
    if (!mesh.normals.empty() && mesh.normals.size() != n)
        return "normals and positions differ in size";
    for (std::size_t v = 0; v < n; ++v)
        if (!finite(mesh.positions[v])) return "vertex " + std::to_string(v) + " is not finite";
    std::vector<std::array<std::uint32_t, 3>> sorted;
    sorted.reserve(mesh.triangles.size());
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        auto tri = mesh.triangles[t];
        for (std::uint32_t v : tri)
            if (v >= n) return "triangle " + std::to_string(t) + " refers to a missing vertex";
        if (tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0])
            return "triangle " + std::to_string(t) + " repeats a vertex";
        std::sort(tri.begin(), tri.end());
        sorted.push_back(tri);
    }
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end())
        return "two triangles have the same three vertices";
    const TopologyReport report = analyze_topology(mesh);
    if (report.nonmanifold_edges != 0) return "an edge is shared by three or more triangles";
    if (report.inconsistently_oriented_edges != 0)
        return "two triangles disagree on orientation across an edge";
    return {};
}

class Refiner::Impl {
  public:
    Impl(std::shared_ptr<const Field> field, const Mesh& first_mesh, RefineSettings settings)
        : settings_(std::move(settings)), constraint_(settings_.constraint) {
        if (!field) throw std::invalid_argument("Refiner: null field");
        if (!settings_.error_measure) settings_.error_measure = std::make_shared<DistanceError>();
        if (!(settings_.swap_ratio > 1.0))
            throw std::invalid_argument("Refiner: swap_ratio must be > 1");
        field_ = std::move(field);
        evaluator_ = field_->make_evaluator();
        split_queue_ = make_queue(settings_.queue, QueueOrder::HighestFirst, settings_.buckets);
        blocked_queue_ = make_queue(settings_.queue, QueueOrder::HighestFirst, settings_.buckets);
        merge_queue_ = make_queue(settings_.queue, QueueOrder::LowestFirst, settings_.buckets);
        load(first_mesh);
        delta_.take();  // the first mesh is the snapshot, not a change
    }

    StepResult step(const StepBudget& budget, bool take_delta);
    void set_field(std::shared_ptr<const Field> field);
    void set_constraint(Constraint c) { constraint_ = std::move(c); }
    const Constraint& constraint() const { return constraint_; }
    std::uint64_t version() const { return version_; }
    MeshStats stats() const;
    QueueEnds queue_ends() const {
        return {split_queue_->extreme_priority(), merge_queue_->extreme_priority()};
    }
    const RefineCounters& counters() const { return counters_; }
    RefinedMesh mesh() const;
    MeshDelta snapshot() const;
    MeshDelta take_delta() { return delta_.take(); }

  private:
    // --- structure
    void load(const Mesh& input);
    void clear_all_into_delta();
    DeltaTriangle delta_triangle(std::uint32_t t) const;
    DeltaVertex delta_vertex(std::uint32_t v) const;
    const glm::dvec3& position(std::uint32_t t, int corner) const {
        return vertices_[triangles_[t].v[corner % 3]].position;
    }
    double base_length(std::uint32_t t) const {
        const Triangle& T = triangles_[t];
        return glm::length(position(t, T.base + 1) - position(t, T.base));
    }
    /// Splittable: every edge at least min_edge_length. Splitting a triangle with a shorter edge
    /// (coincident vertices in the input) would only make more degenerate triangles.
    bool splittable(std::uint32_t t) const {
        for (int e = 0; e < 3; ++e)
            if (!(glm::length(position(t, e + 1) - position(t, e)) >= settings_.min_edge_length))
                return false;
        return true;
    }
    bool is_diamond(std::uint32_t t, std::uint32_t n) const {
        return n != kNone && triangles_[n].nb[triangles_[n].base] == t;
    }
    void replace_neighbour(std::uint32_t t, std::uint32_t old_nb, std::uint32_t new_nb);

    // --- errors and queues
    ProjectionRequest candidate_request(std::uint32_t t) const;
    /// Projects the base midpoints of `tris` that lack a current one (one batched projection).
    void ensure_candidates(std::span<const std::uint32_t> tris);
    TriangleGeometry geometry(std::uint32_t t) const;
    /// Brings the errors of `tris` to the current version (one batched evaluation). A split
    /// triangle's projected midpoint is the vertex its split created.
    void ensure_errors(std::span<const std::uint32_t> tris);
    /// Makes t a leaf; its error must be current.
    void add_leaf(std::uint32_t t);
    void remove_leaf(std::uint32_t t);
    double parent_error(std::uint32_t parent);
    double merge_priority(std::uint32_t record);
    void child_became_leaf(std::uint32_t record);
    void child_was_split(std::uint32_t record);

    // --- operations
    bool plan_split(std::uint32_t t, SplitPlan& plan);
    void execute(const SplitPlan& plan);
    void bisect(std::uint32_t t, std::uint32_t partner);
    std::uint32_t make_child(std::uint32_t record, std::array<std::uint32_t, 3> v,
                             std::array<std::uint32_t, 3> nb, std::uint8_t base);
    void merge(std::uint32_t record);
    MeshStats stats_after_merge(const MeshStats& stats, std::uint32_t record);
    bool acceptable_split(const MeshStats& stats, const SplitPlan& plan) const;
    bool find_split(const MeshStats& stats, SplitPlan& plan);
    bool conflicts(const SplitPlan& plan, std::uint32_t record) const;
    std::size_t act();  // one split, merge or exchange; returns operations done, 0 when idle
    std::size_t try_exchange(const MeshStats& stats);
    bool choose_merges(const MeshStats& stats, const SplitPlan& plan, double below);

    // --- function versions
    bool refresh_pending() const;
    /// Refreshes up to `limit` (> 0) items of the current stage; returns how many.
    std::size_t refresh_some(std::size_t limit);
    void refresh_vertices(std::span<const std::uint32_t> vertices);
    void refresh_leaves(std::span<const std::uint32_t> leaves);
    void refresh_records(std::span<const std::uint32_t> records);
    void restart();

    RefineSettings settings_;
    Constraint constraint_;
    std::shared_ptr<const Field> field_;
    std::unique_ptr<Evaluator> evaluator_;
    std::uint64_t version_ = 1;

    Pool<Vertex> vertices_;
    Pool<Triangle> triangles_;
    Pool<SplitRecord> records_;
    std::unique_ptr<PriorityQueue> split_queue_;    // leaves that may be split
    std::unique_ptr<PriorityQueue> blocked_queue_;  // leaves too small to split
    std::unique_ptr<PriorityQueue> merge_queue_;    // records whose children are all leaves
    std::size_t leaf_count_ = 0;
    CompensatedSum total_error_;
    double root_edge_length_ = 0.0;  // mean edge length of the phase-1 mesh
    Box bounds_;                     // bounding box of the phase-1 mesh
    bool has_boundary_ = false;      // some edge has one triangle (then splits may add 1)

    std::uint32_t next_vertex_id_ = 0;
    std::uint32_t next_triangle_id_ = 0;
    DeltaBuilder delta_;
    RefineCounters counters_;
    SplitPlan plan_;  // scratch
    std::vector<std::uint32_t> exchange_merges_;
    std::vector<std::uint32_t> stale_, pending_;
    std::vector<ProjectionRequest> requests_;
    std::vector<Projection> projections_;
    std::vector<TriangleGeometry> geometries_;
    std::vector<double> errors_;

    // Refresh after set_field: vertices, then leaves, then mergeable records.
    enum class RefreshStage : std::uint8_t { None, Vertices, Leaves, Records };
    RefreshStage refresh_stage_ = RefreshStage::None;
    std::vector<std::uint32_t> refresh_list_;
    std::size_t refresh_next_ = 0;
    std::optional<Mesh> fresh_phase1_;  // the new function's phase-1 mesh, if computed
    bool restart_pending_ = false;
};

// ---------------------------------------------------------------------------------------------
// Structure

void Refiner::Impl::load(const Mesh& input) {
    const std::string problem = validate_refinable(input);
    if (!problem.empty()) throw std::invalid_argument("Refiner: " + problem);
    Mesh mesh = input;
    build_adjacency(mesh);

    std::vector<std::uint32_t> slot_of(mesh.positions.size(), kNone);
    for (const auto& tri : mesh.triangles)
        for (std::uint32_t v : tri) slot_of[v] = 0;  // mark used vertices
    bounds_ = {glm::dvec3(std::numeric_limits<double>::infinity()),
               glm::dvec3(-std::numeric_limits<double>::infinity())};
    for (std::uint32_t v = 0; v < mesh.positions.size(); ++v) {
        if (slot_of[v] == kNone) continue;
        bounds_.lo = glm::min(bounds_.lo, mesh.positions[v]);
        bounds_.hi = glm::max(bounds_.hi, mesh.positions[v]);
    }
    for (std::uint32_t v = 0; v < mesh.positions.size(); ++v) {
        if (slot_of[v] == kNone) continue;
        const std::uint32_t slot = vertices_.allocate();
        slot_of[v] = slot;
        Vertex& V = vertices_[slot];
        V.id = next_vertex_id_++;
        V.position = mesh.positions[v];
        const glm::dvec3 gradient = evaluator_->value_gradient(V.position).gradient;
        V.normal = mesh.normals.empty() ? glm::dvec3(0.0) : mesh.normals[v];
        if (V.normal == glm::dvec3(0.0) || !finite(V.normal)) V.normal = unit_or_zero(gradient);
        V.gradient_norm = finite(gradient) ? glm::length(gradient) : 0.0;
        V.scale = std::numeric_limits<double>::infinity();
        V.version = version_;
        V.alive = true;
        delta_.add_vertex(delta_vertex(slot));
    }
    // Triangle slots are allocated in input order, so slot t' of input triangle t is known.
    std::vector<std::uint32_t> tri_slot(mesh.triangles.size());
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) tri_slot[t] = triangles_.allocate();
    double edge_sum = 0.0;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        Triangle& T = triangles_[tri_slot[t]];
        T.id = next_triangle_id_++;
        T.base = mesh.base_edge[t];
        for (int e = 0; e < 3; ++e) {
            T.v[e] = slot_of[mesh.triangles[t][e]];
            const std::uint32_t n = mesh.neighbours[t][e];
            T.nb[e] = n == kNoNeighbour ? kNone : tri_slot[n];
        }
        for (int e = 0; e < 3; ++e) {
            Vertex& a = vertices_[T.v[e]];
            Vertex& b = vertices_[T.v[(e + 1) % 3]];
            const double length = glm::length(b.position - a.position);
            edge_sum += length;
            a.scale = std::min(a.scale, length);
            b.scale = std::min(b.scale, length);
            if (T.nb[e] == kNone) {
                has_boundary_ = true;
                const std::int8_t axis = face_axis(a.position, b.position, bounds_);
                if (a.fixed_axis < 0) a.fixed_axis = axis;
                if (b.fixed_axis < 0) b.fixed_axis = axis;
            }
        }
    }
    root_edge_length_ = mesh.triangles.empty() ? 0.0 : edge_sum / (3.0 * mesh.triangles.size());
    ensure_errors(tri_slot);
    for (std::uint32_t slot : tri_slot) add_leaf(slot);
}

void Refiner::Impl::clear_all_into_delta() {
    for (std::uint32_t t = 0; t < triangles_.size(); ++t)
        if (triangles_[t].state == TriangleState::Leaf) delta_.remove_triangle(triangles_[t].id);
    for (std::uint32_t v = 0; v < vertices_.size(); ++v)
        if (vertices_[v].alive) delta_.remove_vertex(vertices_[v].id);
    vertices_.clear();
    triangles_.clear();
    records_.clear();
    split_queue_->clear();
    blocked_queue_->clear();
    merge_queue_->clear();
    leaf_count_ = 0;
    total_error_.clear();
    has_boundary_ = false;
}

DeltaTriangle Refiner::Impl::delta_triangle(std::uint32_t t) const {
    const Triangle& T = triangles_[t];
    return {T.id, {vertices_[T.v[0]].id, vertices_[T.v[1]].id, vertices_[T.v[2]].id}};
}

DeltaVertex Refiner::Impl::delta_vertex(std::uint32_t v) const {
    const Vertex& V = vertices_[v];
    return {V.id, V.position, V.normal};
}

void Refiner::Impl::replace_neighbour(std::uint32_t t, std::uint32_t old_nb, std::uint32_t new_nb) {
    if (t == kNone) return;
    for (std::uint32_t& n : triangles_[t].nb) {
        if (n == old_nb) {
            n = new_nb;
            return;
        }
    }
    assert(false && "replace_neighbour: not adjacent");
}

// ---------------------------------------------------------------------------------------------
// Errors and queues

ProjectionRequest Refiner::Impl::candidate_request(std::uint32_t t) const {
    const Triangle& T = triangles_[t];
    const Vertex& a = vertices_[T.v[T.base]];
    const Vertex& b = vertices_[T.v[(T.base + 1) % 3]];
    // Symmetric in a and b, so that both triangles of a diamond compute the same point.
    ProjectionRequest request;
    request.start = 0.5 * (a.position + b.position);
    request.direction = a.normal + b.normal;
    request.slope = 0.5 * (a.gradient_norm + b.gradient_norm);
    request.scale = glm::length(b.position - a.position);
    request.fixed_axis = T.nb[T.base] == kNone ? face_axis(a.position, b.position, bounds_) : -1;
    if (!(request.scale > 0.0)) request.scale = settings_.min_edge_length;
    return request;
}

void Refiner::Impl::ensure_candidates(std::span<const std::uint32_t> tris) {
    pending_.clear();
    requests_.clear();
    for (std::uint32_t t : tris) {
        Triangle& T = triangles_[t];
        if (T.candidate_version == version_) continue;
        const std::uint32_t n = T.nb[T.base];
        if (is_diamond(t, n) && triangles_[n].candidate_version == version_) {
            const Triangle& N = triangles_[n];  // the diamond partner's is the same point
            T.candidate = N.candidate;
            T.candidate_normal = N.candidate_normal;
            T.candidate_gradient_norm = N.candidate_gradient_norm;
            T.candidate_on_surface = N.candidate_on_surface;
            T.candidate_version = version_;
            continue;
        }
        pending_.push_back(t);
        requests_.push_back(candidate_request(t));
    }
    projections_.resize(requests_.size());
    project_to_surface(*evaluator_, requests_, projections_, settings_.projection);
    for (std::size_t i = 0; i < pending_.size(); ++i) {
        Triangle& T = triangles_[pending_[i]];
        const Projection& p = projections_[i];
        T.candidate = p.position;
        T.candidate_normal = p.on_surface() ? p.normal : unit_or_zero(requests_[i].direction);
        T.candidate_gradient_norm = p.gradient_norm;
        T.candidate_on_surface = p.on_surface();
        T.candidate_version = version_;
    }
}

TriangleGeometry Refiner::Impl::geometry(std::uint32_t t) const {
    const Triangle& T = triangles_[t];
    double gradient_norm = 0.0;  // the mean over the corners, or 0 if one is unknown
    for (std::uint32_t v : T.v) {
        const double g = vertices_[v].gradient_norm;
        gradient_norm = g > 0.0 && gradient_norm >= 0.0 ? gradient_norm + g / 3.0 : -1.0;
    }
    const glm::dvec3 midpoint = T.state == TriangleState::Split
                                    ? vertices_[records_[T.split].vertex].position
                                    : T.candidate;
    return {position(t, T.base), position(t, T.base + 1), position(t, T.base + 2), midpoint,
            std::max(gradient_norm, 0.0)};
}

void Refiner::Impl::ensure_errors(std::span<const std::uint32_t> tris) {
    stale_.clear();
    for (std::uint32_t t : tris)
        if (triangles_[t].error_version != version_) stale_.push_back(t);
    if (stale_.empty()) return;
    // The base midpoint is projected here only for measures that read it; otherwise only when
    // the triangle is split.
    if (settings_.error_measure->needs_projected_midpoint()) {
        std::vector<std::uint32_t> leaves;
        for (std::uint32_t t : stale_)
            if (triangles_[t].state != TriangleState::Split) leaves.push_back(t);
        ensure_candidates(leaves);
    }
    geometries_.clear();
    for (std::uint32_t t : stale_) geometries_.push_back(geometry(t));
    errors_.resize(stale_.size());
    settings_.error_measure->triangle_errors(*evaluator_, geometries_, errors_);
    for (std::size_t i = 0; i < stale_.size(); ++i) {
        Triangle& T = triangles_[stale_[i]];
        T.error = errors_[i] >= 0.0 ? errors_[i] : 0.0;  // NaN or negative from a custom measure
        T.error_version = version_;
    }
}

void Refiner::Impl::add_leaf(std::uint32_t t) {
    Triangle& T = triangles_[t];
    T.state = TriangleState::Leaf;
    T.split = kNone;
    ++leaf_count_;
    assert(T.error_version == version_);
    const double error = T.error;
    total_error_.add(error);
    PriorityQueue& queue = splittable(t) ? *split_queue_ : *blocked_queue_;
    queue.insert(t, error);
    delta_.add_triangle(delta_triangle(t));
}

void Refiner::Impl::remove_leaf(std::uint32_t t) {
    const Triangle& T = triangles_[t];
    assert(T.state == TriangleState::Leaf);
    if (split_queue_->contains(t))
        split_queue_->remove(t);
    else
        blocked_queue_->remove(t);
    total_error_.add(-T.error);
    --leaf_count_;
    delta_.remove_triangle(T.id);
}

double Refiner::Impl::parent_error(std::uint32_t parent) {
    ensure_errors({&parent, 1});
    return triangles_[parent].error;
}

double Refiner::Impl::merge_priority(std::uint32_t record) {
    const SplitRecord& R = records_[record];
    const std::size_t n = R.parents[1] == kNone ? 1 : 2;
    ensure_errors({R.parents.data(), n});
    double priority = triangles_[R.parents[0]].error;
    if (n == 2) priority = std::max(priority, triangles_[R.parents[1]].error);
    return priority;
}

void Refiner::Impl::child_became_leaf(std::uint32_t record) {
    if (record == kNone) return;
    SplitRecord& R = records_[record];
    assert(R.split_children > 0);
    if (--R.split_children == 0) merge_queue_->insert(record, merge_priority(record));
}

void Refiner::Impl::child_was_split(std::uint32_t record) {
    if (record == kNone) return;
    SplitRecord& R = records_[record];
    if (R.split_children++ == 0) merge_queue_->remove(record);
}

// ---------------------------------------------------------------------------------------------
// Splits

bool Refiner::Impl::plan_split(std::uint32_t t, SplitPlan& plan) {
    plan.chain.clear();
    plan.added_triangles = 0;
    for (std::uint32_t current = t;;) {
        if (!splittable(current)) return false;
        plan.chain.push_back(current);
        const std::uint32_t n = triangles_[current].nb[triangles_[current].base];
        if (n == kNone || is_diamond(current, n)) {
            if (n != kNone && !splittable(n)) return false;
            plan.partner = n;
            plan.added_triangles += n == kNone ? 1 : 2;
            return true;
        }
        plan.added_triangles += 2;
        if (plan.chain.size() > settings_.max_forced_chain) {
            ++counters_.refused_splits;
            return false;
        }
        current = n;
    }
}

void Refiner::Impl::execute(const SplitPlan& plan) {
    // Bisect from the far end of the chain back to the triangle that asked: after chain[i + 1] is
    // bisected, its child across chain[i]'s base edge has that edge as its own base edge.
    bisect(plan.chain.back(), plan.partner);
    for (std::size_t i = plan.chain.size() - 1; i-- > 0;) {
        const std::uint32_t t = plan.chain[i];
        const std::uint32_t n = triangles_[t].nb[triangles_[t].base];
        assert(is_diamond(t, n));
        bisect(t, n);
    }
}

std::uint32_t Refiner::Impl::make_child(std::uint32_t record, std::array<std::uint32_t, 3> v,
                                        std::array<std::uint32_t, 3> nb, std::uint8_t base) {
    const std::uint32_t slot = triangles_.allocate();
    Triangle& C = triangles_[slot];
    C.id = next_triangle_id_++;
    C.v = v;
    C.nb = nb;
    C.base = base;
    C.parent = record;
    return slot;
}

void Refiner::Impl::bisect(std::uint32_t t, std::uint32_t n) {
    const std::array<std::uint32_t, 2> pair{t, n};
    ensure_errors({pair.data(), n == kNone ? 1u : 2u});
    ensure_candidates({&t, 1});
    const std::uint32_t record = records_.allocate();
    const std::uint32_t m = vertices_.allocate();
    {
        const Triangle& T = triangles_[t];
        Vertex& M = vertices_[m];
        M.id = next_vertex_id_++;
        M.position = T.candidate;
        M.normal = T.candidate_normal;
        M.gradient_norm = T.candidate_gradient_norm;
        M.on_surface = T.candidate_on_surface;
        M.scale = base_length(t);
        M.version = version_;
        M.fixed_axis = n == kNone ? vertices_[T.v[T.base]].fixed_axis : -1;
        M.alive = true;
        if (!M.on_surface) ++counters_.failed_projections;
        delta_.add_vertex(delta_vertex(m));
    }
    remove_leaf(t);
    if (n != kNone) remove_leaf(n);

    // T = (a, b, c) with base a-b becomes (a, m, c) and (m, b, c); N = (b, a, d) becomes
    // (b, m, d) and (m, a, d). Neighbour slots across the half-base edges are filled below.
    const std::array<std::uint32_t, 2> parents{t, n};
    std::array<std::uint32_t, 4> children{kNone, kNone, kNone, kNone};
    for (int side = 0; side < 2; ++side) {
        const std::uint32_t p = parents[side];
        if (p == kNone) continue;
        const Triangle P = triangles_[p];
        const int b = P.base;
        const std::uint32_t a = P.v[b], bb = P.v[(b + 1) % 3], c = P.v[(b + 2) % 3];
        const std::uint32_t first =
            make_child(record, {a, m, c}, {kNone, kNone, P.nb[(b + 2) % 3]}, 2);
        const std::uint32_t second =
            make_child(record, {m, bb, c}, {kNone, P.nb[(b + 1) % 3], first}, 1);
        triangles_[first].nb[1] = second;
        replace_neighbour(P.nb[(b + 2) % 3], p, first);
        replace_neighbour(P.nb[(b + 1) % 3], p, second);
        children[2 * side] = first;
        children[2 * side + 1] = second;
        Triangle& Pm = triangles_[p];
        Pm.state = TriangleState::Split;
        Pm.split = record;
        child_was_split(Pm.parent);
    }
    if (n != kNone) {  // (a, m) borders (m, a); (m, b) borders (b, m)
        triangles_[children[0]].nb[0] = children[3];
        triangles_[children[3]].nb[0] = children[0];
        triangles_[children[1]].nb[0] = children[2];
        triangles_[children[2]].nb[0] = children[1];
    }
    SplitRecord& R = records_[record];
    R.vertex = m;
    R.parents = parents;
    R.children = children;
    R.split_children = 0;
    R.alive = true;
    const std::size_t child_count = n == kNone ? 2 : 4;
    ensure_errors({children.data(), child_count});
    for (std::size_t i = 0; i < child_count; ++i) add_leaf(children[i]);
    merge_queue_->insert(record, merge_priority(record));
    ++counters_.splits;
}

// ---------------------------------------------------------------------------------------------
// Merges

void Refiner::Impl::merge(std::uint32_t record) {
    merge_queue_->remove(record);
    const SplitRecord R = records_[record];
    assert(R.alive && R.split_children == 0);
    for (std::uint32_t c : R.children)
        if (c != kNone) remove_leaf(c);
    const Vertex& M = vertices_[R.vertex];
    for (int side = 0; side < 2; ++side) {
        const std::uint32_t p = R.parents[side];
        if (p == kNone) continue;
        const std::uint32_t first = R.children[2 * side], second = R.children[2 * side + 1];
        Triangle& P = triangles_[p];
        const int b = P.base;
        P.nb[(b + 2) % 3] = triangles_[first].nb[2];
        P.nb[(b + 1) % 3] = triangles_[second].nb[1];
        replace_neighbour(P.nb[(b + 2) % 3], first, p);
        replace_neighbour(P.nb[(b + 1) % 3], second, p);
        // The removed vertex is the parent's projected base midpoint.
        P.candidate = M.position;
        P.candidate_normal = M.normal;
        P.candidate_gradient_norm = M.gradient_norm;
        P.candidate_on_surface = M.on_surface;
        P.candidate_version = M.version;
    }
    delta_.remove_vertex(M.id);
    vertices_[R.vertex].alive = false;
    vertices_.release(R.vertex);
    for (std::uint32_t c : R.children) {
        if (c == kNone) continue;
        triangles_[c].state = TriangleState::Free;
        triangles_.release(c);
    }
    records_[record].alive = false;
    records_.release(record);
    for (std::uint32_t p : R.parents) {
        if (p == kNone) continue;
        triangles_[p].state = TriangleState::Leaf;  // its midpoint is now its candidate
        ensure_errors({&p, 1});
        add_leaf(p);
        child_became_leaf(triangles_[p].parent);
    }
    ++counters_.merges;
}

MeshStats Refiner::Impl::stats_after_merge(const MeshStats& stats, std::uint32_t record) {
    const SplitRecord& R = records_[record];
    MeshStats after = stats;
    for (std::uint32_t c : R.children) {
        if (c == kNone) continue;
        --after.triangles;
        after.total_error -= triangles_[c].error;
    }
    for (std::uint32_t p : R.parents) {
        if (p == kNone) continue;
        ++after.triangles;
        const double e = parent_error(p);
        after.total_error += e;
        after.max_error = std::max(after.max_error, e);  // an upper bound: children leave
    }
    return after;
}

// ---------------------------------------------------------------------------------------------
// Choosing operations

bool Refiner::Impl::acceptable_split(const MeshStats& stats, const SplitPlan& plan) const {
    // Never overshoot: the constraint must still want refinement just before the last bisection
    // of the chain, and the mesh after it must not break a cap.
    MeshStats before_last = stats;
    before_last.triangles += plan.added_triangles - 1;
    MeshStats after = stats;
    after.triangles += plan.added_triangles;
    return constraint_.wants_refinement(before_last) && !constraint_.over_limit(after);
}

bool Refiner::Impl::conflicts(const SplitPlan& plan, std::uint32_t record) const {
    if (record == kNone) return false;
    const auto& children = records_[record].children;
    auto is_child = [&](std::uint32_t t) {
        return t != kNone && std::find(children.begin(), children.end(), t) != children.end();
    };
    return is_child(plan.partner) || std::any_of(plan.chain.begin(), plan.chain.end(), is_child);
}

bool Refiner::Impl::find_split(const MeshStats& stats, SplitPlan& plan) {
    // Quick refusals before scanning the queue: a split adds at least 1 triangle, and at least 2
    // on a closed mesh.
    SplitPlan smallest;
    smallest.added_triangles = has_boundary_ ? 1 : 2;
    if (!acceptable_split(stats, smallest)) return false;
    // The common case: the top of the queue fits.
    const std::uint32_t top = split_queue_->top();
    if (top == kNone) return false;
    if (plan_split(top, plan) && acceptable_split(stats, plan)) return true;
    bool found = false;
    split_queue_->visit_in_order([&](std::uint32_t t) {
        found = plan_split(t, plan) && acceptable_split(stats, plan);
        return found;
    });
    return found;
}

bool Refiner::Impl::choose_merges(const MeshStats& stats, const SplitPlan& plan, double below) {
    // The cheapest merges (each worth less than `below`) that make room for the split.
    constexpr std::size_t kMaxMerges = 8;
    exchange_merges_.clear();
    MeshStats after = stats;
    bool enough = false;
    int skipped = 0;
    merge_queue_->visit_in_order([&](std::uint32_t record) {
        if (exchange_merges_.size() == kMaxMerges) return true;
        // Bucket order is approximate: look a little past a record that is too dear.
        if (!(merge_queue_->priority(record) < below)) return ++skipped > int(kMaxMerges);
        if (conflicts(plan, record)) return false;
        after = stats_after_merge(after, record);
        exchange_merges_.push_back(record);
        enough = acceptable_split(after, plan);
        return enough;
    });
    return enough;
}

std::size_t Refiner::Impl::try_exchange(const MeshStats& stats) {
    // ROAM's optimisation at a fixed budget: undo the cheapest splits to make room for a better
    // one, when it is worth swap_ratio times more than each split undone. The best few splits are
    // tried, as a long forced chain may need more room than the cheap merges give.
    const std::uint32_t cheapest = merge_queue_->top();
    if (cheapest == kNone) return 0;
    const double threshold = settings_.swap_ratio * merge_queue_->priority(cheapest);
    constexpr int kCandidates = 16;
    int examined = 0;
    bool found = false;
    split_queue_->visit_in_order([&](std::uint32_t t) {
        if (++examined > kCandidates) return true;
        const double priority = split_queue_->priority(t);
        if (!(priority > threshold)) return false;  // bucket order is approximate: look further
        found =
            plan_split(t, plan_) && choose_merges(stats, plan_, priority / settings_.swap_ratio);
        return found;
    });
    if (!found) return 0;
    for (std::uint32_t record : exchange_merges_) merge(record);
    execute(plan_);
    ++counters_.swaps;
    return exchange_merges_.size() + plan_.bisections();
}

std::size_t Refiner::Impl::act() {
    const MeshStats current = stats();
    if (constraint_.wants_refinement(current) && find_split(current, plan_)) {
        execute(plan_);
        return plan_.bisections();
    }
    const std::uint32_t record = merge_queue_->top();
    if (record == kNone) return 0;
    if (constraint_.over_limit(current) ||
        !constraint_.wants_refinement(stats_after_merge(current, record))) {
        merge(record);
        return 1;
    }
    return try_exchange(current);
}

// ---------------------------------------------------------------------------------------------
// Function versions

void Refiner::Impl::set_field(std::shared_ptr<const Field> field) {
    if (!field) throw std::invalid_argument("Refiner::set_field: null field");
    field_ = std::move(field);
    evaluator_ = field_->make_evaluator();
    ++version_;
    restart_pending_ = false;
    fresh_phase1_.reset();
    if (settings_.phase1) {
        fresh_phase1_ = settings_.phase1(*field_);
        if (!same_topology(analyze_topology(*fresh_phase1_), analyze_topology(mesh().mesh))) {
            restart_pending_ = true;
            return;
        }
    }
    // The most outdated vertices first (when the function changes faster than the refresh
    // completes, no vertex is left behind), then in id order: coarse before fine.
    refresh_list_.clear();
    for (std::uint32_t v = 0; v < vertices_.size(); ++v)
        if (vertices_[v].alive) refresh_list_.push_back(v);
    std::sort(refresh_list_.begin(), refresh_list_.end(), [&](std::uint32_t a, std::uint32_t b) {
        const Vertex &va = vertices_[a], &vb = vertices_[b];
        return va.version != vb.version ? va.version < vb.version : va.id < vb.id;
    });
    refresh_next_ = 0;
    refresh_stage_ = RefreshStage::Vertices;
}

bool Refiner::Impl::refresh_pending() const {
    return refresh_stage_ != RefreshStage::None;
}

std::size_t Refiner::Impl::refresh_some(std::size_t limit) {
    while (refresh_next_ == refresh_list_.size()) {
        refresh_list_.clear();
        refresh_next_ = 0;
        if (refresh_stage_ == RefreshStage::Vertices) {
            refresh_stage_ = RefreshStage::Leaves;
            for (std::uint32_t t = 0; t < triangles_.size(); ++t)
                if (triangles_[t].state == TriangleState::Leaf) refresh_list_.push_back(t);
        } else if (refresh_stage_ == RefreshStage::Leaves) {
            refresh_stage_ = RefreshStage::Records;
            for (std::uint32_t r = 0; r < records_.size(); ++r)
                if (merge_queue_->contains(r)) refresh_list_.push_back(r);
        } else {
            refresh_stage_ = RefreshStage::None;
            return 0;
        }
    }
    // Items are refreshed in batches (batched evaluations); each item's result does not depend
    // on the batch it is in, so neither does the mesh depend on the step sizes.
    constexpr std::size_t kBatch = 256;
    const std::size_t count = std::min({limit, kBatch, refresh_list_.size() - refresh_next_});
    const std::span<const std::uint32_t> items(refresh_list_.data() + refresh_next_, count);
    refresh_next_ += count;
    if (refresh_stage_ == RefreshStage::Vertices)
        refresh_vertices(items);
    else if (refresh_stage_ == RefreshStage::Leaves)
        refresh_leaves(items);
    else
        refresh_records(items);
    return count;
}

void Refiner::Impl::refresh_vertices(std::span<const std::uint32_t> items) {
    requests_.clear();
    for (std::uint32_t v : items) {
        const Vertex& V = vertices_[v];
        ProjectionRequest request;
        request.start = V.position;
        request.direction = V.normal;
        request.slope = V.gradient_norm;
        // The phase-1 edge length bounds how far a vertex may travel: beyond it the phase-1
        // topology guarantee says nothing, and the fresh phase-1 mesh takes over.
        request.scale = 2.0 * std::max(root_edge_length_, V.scale);
        request.fixed_axis = V.fixed_axis;
        requests_.push_back(request);
    }
    projections_.resize(requests_.size());
    project_to_surface(*evaluator_, requests_, projections_, settings_.projection);
    for (std::size_t i = 0; i < items.size(); ++i) {
        Vertex& V = vertices_[items[i]];
        const Projection& p = projections_[i];
        if (p.on_surface()) {
            V.position = p.position;
            V.normal = p.normal;
            V.gradient_norm = p.gradient_norm;
        } else {
            ++counters_.failed_refreshes;
            if (fresh_phase1_) restart_pending_ = true;
        }
        V.on_surface = p.on_surface();
        V.version = version_;
        delta_.move_vertex(delta_vertex(items[i]));
    }
    counters_.refreshed_vertices += items.size();
}

void Refiner::Impl::refresh_leaves(std::span<const std::uint32_t> items) {
    std::vector<double> old_errors;
    old_errors.reserve(items.size());
    for (std::uint32_t t : items) old_errors.push_back(triangles_[t].error);
    ensure_errors(items);
    for (std::size_t i = 0; i < items.size(); ++i) {
        const std::uint32_t t = items[i];
        const double error = triangles_[t].error;
        total_error_.add(error - old_errors[i]);
        PriorityQueue& queue = split_queue_->contains(t) ? *split_queue_ : *blocked_queue_;
        queue.update(t, error);
    }
    counters_.refreshed_triangles += items.size();
}

void Refiner::Impl::refresh_records(std::span<const std::uint32_t> items) {
    std::vector<std::uint32_t> parents;
    for (std::uint32_t r : items)
        for (std::uint32_t p : records_[r].parents)
            if (p != kNone) parents.push_back(p);
    ensure_errors(parents);
    for (std::uint32_t r : items) merge_queue_->update(r, merge_priority(r));
}

void Refiner::Impl::restart() {
    assert(fresh_phase1_);
    clear_all_into_delta();
    Mesh fresh = std::move(*fresh_phase1_);
    fresh_phase1_.reset();
    restart_pending_ = false;
    refresh_stage_ = RefreshStage::None;
    refresh_list_.clear();
    load(fresh);
    ++counters_.restarts;
}

// ---------------------------------------------------------------------------------------------
// Steps and views

StepResult Refiner::Impl::step(const StepBudget& budget, bool take) {
    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    const RefineCounters before = counters_;
    StepResult result;
    std::size_t operations = 0;
    while (operations < budget.operations) {
        if (settings_.cancel && settings_.cancel->load(std::memory_order_relaxed)) {
            result.cancelled = true;
            break;
        }
        if (budget.microseconds > 0 &&
            Clock::now() - start >= std::chrono::microseconds(budget.microseconds))
            break;
        if (restart_pending_) {
            restart();
            result.restarted = true;
            ++operations;
        } else if (refresh_pending()) {
            const std::size_t done = refresh_some(budget.operations - operations);
            result.refreshed += done;
            operations += done;
        } else if (const std::size_t done = act(); done > 0) {
            operations += done;
        } else {
            result.converged = true;
            break;
        }
    }
    result.splits = counters_.splits - before.splits;
    result.merges = counters_.merges - before.merges;
    if (take) result.delta = delta_.take();
    return result;
}

MeshStats Refiner::Impl::stats() const {
    MeshStats s;
    s.triangles = leaf_count_;
    s.total_error = std::max(0.0, total_error_.value());
    s.max_error = std::max(split_queue_->extreme_priority(), blocked_queue_->extreme_priority());
    return s;
}

RefinedMesh Refiner::Impl::mesh() const {
    RefinedMesh out;
    std::vector<std::uint32_t> leaves, verts;
    for (std::uint32_t t = 0; t < triangles_.size(); ++t)
        if (triangles_[t].state == TriangleState::Leaf) leaves.push_back(t);
    for (std::uint32_t v = 0; v < vertices_.size(); ++v)
        if (vertices_[v].alive) verts.push_back(v);
    std::sort(leaves.begin(), leaves.end(), [&](std::uint32_t a, std::uint32_t b) {
        return triangles_[a].id < triangles_[b].id;
    });
    std::sort(verts.begin(), verts.end(),
              [&](std::uint32_t a, std::uint32_t b) { return vertices_[a].id < vertices_[b].id; });
    std::vector<std::uint32_t> vertex_index(vertices_.size(), kNone);
    std::vector<std::uint32_t> triangle_index(triangles_.size(), kNone);
    for (std::uint32_t i = 0; i < verts.size(); ++i) {
        vertex_index[verts[i]] = i;
        out.mesh.positions.push_back(vertices_[verts[i]].position);
        out.mesh.normals.push_back(vertices_[verts[i]].normal);
        out.vertex_ids.push_back(vertices_[verts[i]].id);
    }
    for (std::uint32_t i = 0; i < leaves.size(); ++i) triangle_index[leaves[i]] = i;
    for (std::uint32_t t : leaves) {
        const Triangle& T = triangles_[t];
        std::array<std::uint32_t, 3> tri{}, nb{};
        for (int e = 0; e < 3; ++e) {
            tri[e] = vertex_index[T.v[e]];
            nb[e] = T.nb[e] == kNone ? kNoNeighbour : triangle_index[T.nb[e]];
        }
        out.mesh.triangles.push_back(tri);
        out.mesh.neighbours.push_back(nb);
        out.mesh.base_edge.push_back(T.base);
        out.triangle_ids.push_back(T.id);
    }
    return out;
}

MeshDelta Refiner::Impl::snapshot() const {
    MeshDelta delta;
    for (std::uint32_t v = 0; v < vertices_.size(); ++v)
        if (vertices_[v].alive) delta.added_vertices.push_back(delta_vertex(v));
    for (std::uint32_t t = 0; t < triangles_.size(); ++t)
        if (triangles_[t].state == TriangleState::Leaf)
            delta.added_triangles.push_back(delta_triangle(t));
    std::sort(delta.added_vertices.begin(), delta.added_vertices.end(),
              [](const DeltaVertex& a, const DeltaVertex& b) { return a.id < b.id; });
    std::sort(delta.added_triangles.begin(), delta.added_triangles.end(),
              [](const DeltaTriangle& a, const DeltaTriangle& b) { return a.id < b.id; });
    return delta;
}

// ---------------------------------------------------------------------------------------------
// Refiner

Refiner::Refiner(std::shared_ptr<const Field> field, const Mesh& first_mesh,
                 RefineSettings settings)
    : impl_(std::make_unique<Impl>(std::move(field), first_mesh, std::move(settings))) {}

namespace {
Mesh run_phase1(const std::shared_ptr<const Field>& field, const RefineSettings& settings) {
    if (!field) throw std::invalid_argument("Refiner: null field");
    if (!settings.phase1) throw std::invalid_argument("Refiner: no phase1 to make the first mesh");
    return settings.phase1(*field);
}
}  // namespace

Refiner::Refiner(std::shared_ptr<const Field> field, RefineSettings settings)
    : Refiner(field, run_phase1(field, settings), settings) {}

Refiner::~Refiner() = default;

StepResult Refiner::step(const StepBudget& budget) {
    return impl_->step(budget, true);
}

StepResult Refiner::run_to_convergence(std::size_t operations_per_step) {
    StepResult total;
    const StepBudget budget{operations_per_step, 0};
    for (;;) {
        const StepResult r = impl_->step(budget, false);
        total.splits += r.splits;
        total.merges += r.merges;
        total.refreshed += r.refreshed;
        total.restarted = total.restarted || r.restarted;
        if (r.converged || r.cancelled) {
            total.converged = r.converged;
            total.cancelled = r.cancelled;
            break;
        }
    }
    total.delta = impl_->take_delta();
    return total;
}

void Refiner::set_constraint(Constraint constraint) {
    impl_->set_constraint(std::move(constraint));
}
const Constraint& Refiner::constraint() const {
    return impl_->constraint();
}
void Refiner::set_field(std::shared_ptr<const Field> field) {
    impl_->set_field(std::move(field));
}
std::uint64_t Refiner::version() const {
    return impl_->version();
}
MeshStats Refiner::stats() const {
    return impl_->stats();
}
QueueEnds Refiner::queue_ends() const {
    return impl_->queue_ends();
}
const RefineCounters& Refiner::counters() const {
    return impl_->counters();
}
RefinedMesh Refiner::mesh() const {
    return impl_->mesh();
}
MeshDelta Refiner::snapshot() const {
    return impl_->snapshot();
}

}  // namespace isomesh
