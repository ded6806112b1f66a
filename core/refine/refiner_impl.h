// Private to core/refine: the state of a Refiner, shared by the files that implement it:
// refiner.cpp (structure, steps, views), triangle_errors.cpp (candidates, errors, queue entries),
// bisection.cpp (splits with their forced splits, merges), dual_queues.cpp (which operation comes
// next) and field_changes.cpp (set_field, reset). See refiner.cpp for the design.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include <glm/geometric.hpp>

#include "mesh/topology.h"
#include "refine/array_memory.h"
#include "refine/refiner.h"

namespace isomesh {
namespace refiner_detail {

inline constexpr std::uint32_t kNone = kNoNeighbour;
static_assert(kNoNeighbour == PriorityQueue::kNone);

enum class TriangleState : std::uint8_t { Leaf, Split, Free };

// 80 bytes: the small fields share the id's word.
struct Vertex {
    std::uint32_t id = 0;
    std::uint8_t fixed_axes = 0;  // on faces of the meshing box: the coordinates that stay (bits)
    bool on_surface = true;
    bool alive = false;
    glm::dvec3 position{0.0};
    glm::dvec3 normal{0.0};
    double gradient_norm = 0.0;  // |grad f| at position; 0 when unknown
    double scale = 0.0;  // the length of the edge it bisected (phase-1: shortest incident edge)
    std::uint64_t version = 0;
};
static_assert(sizeof(Vertex) == 80);

// The fields a split's planning reads (connectivity, state, versions) come first: they fill the
// first 64 bytes, one cache line (the pool is 64-byte aligned), and planning a split touches the
// triangles of its chain in random order. The candidate and the error follow.
struct Triangle {
    std::uint32_t id = 0;
    std::array<std::uint32_t, 3> v{};   // vertex slots, counter-clockwise
    std::array<std::uint32_t, 3> nb{};  // triangle slot across edge v[e]-v[e+1], or kNone
    std::uint32_t parent = kNone;       // the split record that created it; kNone for roots
    std::uint32_t split = kNone;        // the split record that replaced it (state Split)
    std::uint8_t base = 0;
    TriangleState state = TriangleState::Free;
    bool candidate_on_surface = false;
    bool candidate_refused = false;  // no valid split vertex at candidate_version: not split
    bool candidate_retried = false;  // the face-normal candidate was tried at candidate_version
    // While the candidate is not current: candidate_gradient_norm holds f at the (unprojected)
    // base midpoint, which the error measure sampled at error_version; its projection starts
    // from it. Cleared by every write of the candidate.
    bool midpoint_value_known = false;
    std::uint64_t candidate_version = 0;
    std::uint64_t error_version = 0;
    // The base midpoint projected onto the surface: the vertex a split would create.
    glm::dvec3 candidate{0.0};
    glm::dvec3 candidate_normal{0.0};
    double candidate_gradient_norm = 0.0;
    double error = 0.0;
};
static_assert(sizeof(Triangle) == 128 && offsetof(Triangle, candidate) == 64);

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
            if (!free_.empty()) prefetch_slot(&items_[free_.back()]);
            items_[slot] = kFresh;
            return slot;
        }
        make_room(items_, items_.size() + 1, wanted_);
        // The slots after the end are written next, a few allocations from now: their lines
        // are asked for now (a write to a line not in the cache waits for it).
        if (items_.size() + kAhead < items_.capacity())
            prefetch_slot(items_.data() + items_.size() + kAhead);
        items_.push_back(kFresh);
        return static_cast<std::uint32_t>(items_.size() - 1);
    }
    void release(std::uint32_t slot) { free_.push_back(slot); }
    void reserve(Reservation n) { wanted_ = isomesh::reserve(items_, n); }
    void clear() {
        items_.clear();
        free_.clear();
    }
    T& operator[](std::uint32_t slot) { return items_[slot]; }
    const T& operator[](std::uint32_t slot) const { return items_[slot]; }
    std::uint32_t size() const { return static_cast<std::uint32_t>(items_.size()); }

  private:
    // A new item is a copy of this one rather than built in place: GCC zeroes a built Triangle
    // with `rep stos`, slow to start for 128 bytes (a fifth of make_child's time); a copy is a
    // few vector moves.
    static inline const T kFresh{};
    static constexpr std::size_t kAhead = 4;
    static void prefetch_slot(const T* item) {
        for (std::size_t line = 0; line < sizeof(T); line += 64)
            __builtin_prefetch(reinterpret_cast<const char*>(item) + line, 1);
    }

    RecycledVector<T> items_;
    std::size_t wanted_ = 0;  // the room reserved for, where growth stops once (make_room)
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

inline bool finite(const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

inline glm::dvec3 unit_or_zero(const glm::dvec3& v) {
    const double length = glm::length(v);
    return length > 0.0 && std::isfinite(length) ? v / length : glm::dvec3(0.0);
}

/// The axes (bit k for axis k) of the faces of the meshing box that a boundary edge a-b lies on:
/// phase 1 puts such edges exactly on the box, which the mesh's bounding box `bounds` touches.
/// Two bits for an edge along an edge of the box. (A plane such as x = 0 has every vertex at
/// x = 0: that axis, flat in `bounds`, is not a face.)
inline std::uint8_t face_axes(const glm::dvec3& a, const glm::dvec3& b, const Box& bounds) {
    std::uint8_t axes = 0;
    for (int k = 0; k < 3; ++k) {
        if (a[k] == b[k] && bounds.lo[k] < bounds.hi[k] &&
            (a[k] == bounds.lo[k] || a[k] == bounds.hi[k]))
            axes |= static_cast<std::uint8_t>(1u << k);
    }
    return axes;
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

}  // namespace refiner_detail

class Refiner::Impl {
  public:
    using Vertex = refiner_detail::Vertex;
    using Triangle = refiner_detail::Triangle;
    using SplitRecord = refiner_detail::SplitRecord;
    using SplitPlan = refiner_detail::SplitPlan;
    template <typename T>
    using Pool = refiner_detail::Pool<T>;
    using CompensatedSum = refiner_detail::CompensatedSum;
    static constexpr std::uint32_t kNone = refiner_detail::kNone;

    Impl(std::shared_ptr<const Field> field, const Mesh& first_mesh, RefineSettings settings);

    StepResult step(const StepBudget& budget, bool take_delta);
    void set_field(std::shared_ptr<const Field> field);
    void set_constraint(Constraint c) {
        constraint_ = std::move(c);
        constraint_reads_max_error_ = constraint_.reads_max_error();
    }
    const Constraint& constraint() const { return constraint_; }
    std::uint64_t version() const { return version_; }
    bool field_change_pending() const { return refresh_pending(); }
    std::size_t vertices_to_move() const {
        return refresh_stage_ == RefreshStage::Vertices ? refresh_list_.size() - refresh_next_ : 0;
    }
    bool refresh_failed() const { return refresh_failed_; }
    void reset(const Mesh& first_mesh);
    const TopologyReport& root_topology() const { return root_topology_; }
    std::uint32_t next_vertex_id() const { return next_vertex_id_; }
    std::uint32_t next_triangle_id() const { return next_triangle_id_; }
    std::size_t inverted_triangles() const;
    /// max_error is left 0 without `with_max_error`: finding it may rescan the top bucket of the
    /// split queue, and most constraints never read it.
    MeshStats stats(bool with_max_error = true) const;
    /// stats() as the constraint sees it.
    MeshStats constraint_stats() const { return stats(constraint_reads_max_error_); }
    QueueEnds queue_ends() const {
        return {split_queue_->extreme_priority(), merge_queue_->extreme_priority()};
    }
    const RefineCounters& counters() const { return counters_; }
    RefinedMesh mesh() const;
    MeshDelta snapshot() const;
    MeshDelta take_delta();

  private:
    // --- structure
    void load(const Mesh& input);
    /// Room in the pools for the refinement the constraint asks for.
    void reserve_for(std::size_t root_triangles);
    /// grad f at the vertices of `mesh`, in one batch; empty when the mesh brought every norm
    /// and normal along.
    std::vector<ValueGradient> missing_gradients(const Mesh& mesh);
    void clear_all_into_delta();
    DeltaTriangle delta_triangle(std::uint32_t t) const;
    DeltaVertex delta_vertex(std::uint32_t v) const;
    const glm::dvec3& position(std::uint32_t t, int corner) const {
        return vertices_[triangles_[t].v[corner % 3]].position;
    }
    const glm::dvec3& normal(std::uint32_t t, int corner) const {
        return vertices_[triangles_[t].v[corner % 3]].normal;
    }
    double base_length(std::uint32_t t) const {
        const Triangle& T = triangles_[t];
        return glm::length(position(t, T.base + 1) - position(t, T.base));
    }
    /// Splittable: every edge at least min_edge_length. Splitting a triangle with a shorter edge
    /// (coincident vertices in the input) would only make more degenerate triangles.
    bool splittable(std::uint32_t t) const {
        const Triangle& T = triangles_[t];
        if (T.candidate_refused && T.candidate_version == version_) return false;
        const double m = settings_.min_edge_length;
        for (int e = 0; e < 3; ++e) {
            const glm::dvec3 edge = position(t, e + 1) - position(t, e);
            // |edge| >= m without the square root where |edge|^2 is clearly larger.
            const double squared = glm::dot(edge, edge);
            if (!(squared > 4.0 * m * m) && !(std::sqrt(squared) >= m)) return false;
        }
        return true;
    }
    bool is_diamond(std::uint32_t t, std::uint32_t n) const {
        return n != kNone && triangles_[n].nb[triangles_[n].base] == t;
    }
    void replace_neighbour(std::uint32_t t, std::uint32_t old_nb, std::uint32_t new_nb);

    // --- errors and queues
    ProjectionRequest candidate_request(std::uint32_t t) const;
    /// candidate_request(t).direction alone.
    glm::dvec3 candidate_direction(std::uint32_t t) const;
    /// Projects the base midpoints of `tris` that lack a current one (one batched projection).
    /// With `look_ahead`, the batch also projects the base midpoints of the leaves next in the
    /// split queue, kept aside for their own splits (projected_ahead).
    void ensure_candidates(std::span<const std::uint32_t> tris, bool look_ahead = false);
    /// Adds to requests_ the leaves after the top of the split queue whose candidates the next
    /// splits will want (their slots to ahead_pending_).
    void request_ahead();
    /// Asks the cache for the memory t's split will touch (of the leaves projected ahead).
    void prefetch_split(std::uint32_t t) const;
    struct AheadProjection;
    /// The projection of t's base midpoint made ahead for the current version, or nullptr.
    AheadProjection* projected_ahead(std::uint32_t t);
    /// The entry holds no projection still to be used.
    bool free_ahead(const AheadProjection& a) const;
    /// Sets t's candidate from the projection of its base midpoint.
    void set_candidate(std::uint32_t t, const Projection& p, const glm::dvec3& direction);
    /// out = t as the error measure sees it; the projected midpoint only `with_midpoint` (the
    /// measure reads it), else zero. Written in place: a returned copy was written in 8-byte
    /// stores and read back in 16-byte loads, which wait for them (a store-forwarding stall).
    void geometry(std::uint32_t t, bool with_midpoint, TriangleGeometry& out) const;
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
    /// Projects the split vertices of the plan; false (and the triangles without one moved to
    /// the blocked queue) when some has none on the surface inside the box.
    bool prepare(const SplitPlan& plan);
    /// Counts t's split as refused and keeps it unsplit (the blocked queue).
    void refuse(std::uint32_t t);
    /// A triangle about to be bisected: its base edge a-b, apex c, and their normals (referring
    /// to the vertices' or candidates' own: a check reads them once, copies would cost more).
    struct SplitCorners {
        const glm::dvec3 &a, &b, &c, &na, &nb, &nc;
    };
    SplitCorners split_corners(std::uint32_t t) const;
    /// Bisecting the base edge at m (normal m_normal) would flip a child against the triangle,
    /// turn one against its corners' normals where the triangle faced along its own, make a
    /// clear fold where there was none, or make a child of zero area.
    static bool folds(const SplitCorners& triangle, const glm::dvec3& m,
                      const glm::dvec3& m_normal);
    /// folds() for both halves of the diamond chain[i]'s split vertex bisects.
    bool split_folds(const SplitPlan& plan, std::size_t i) const;
    /// Where the base midpoint projected along the vertex normals folds the diamond, tries it
    /// along the diamond's face normals instead; true (and chain[i]'s candidate, and its
    /// partner's, replaced) when that one is valid.
    bool retry_candidate(const SplitPlan& plan, std::size_t i);
    void execute(const SplitPlan& plan);
    void bisect(std::uint32_t t, std::uint32_t partner);
    /// A new triangle slot, child of `record` with base edge `base` (its corners and neighbours
    /// for the caller to set).
    std::uint32_t make_child(std::uint32_t record, std::uint8_t base);
    void merge(std::uint32_t record);
    MeshStats stats_after_merge(const MeshStats& stats, std::uint32_t record);
    bool acceptable_split(const MeshStats& stats, const SplitPlan& plan) const;
    bool find_split(const MeshStats& stats, SplitPlan& plan);
    /// Moves leaf t from the split queue to the blocked queue.
    void block(std::uint32_t t);
    bool conflicts(const SplitPlan& plan, std::uint32_t record) const;
    std::size_t act();  // one split, merge or exchange; returns operations done, 0 when idle
    std::size_t try_exchange(const MeshStats& stats);
    bool choose_merges(const MeshStats& stats, const SplitPlan& plan, double below);

    // --- function versions
    bool refresh_pending() const;
    /// Refreshes up to `limit` (> 0) items of the current stage; returns how many.
    std::size_t refresh_some(std::size_t limit);
    void skip_finished_refresh_stages();
    void refresh_vertices(std::span<const std::uint32_t> vertices);
    void refresh_leaves(std::span<const std::uint32_t> leaves);
    void refresh_records(std::span<const std::uint32_t> records);

    RefineSettings settings_;
    Constraint constraint_;
    bool constraint_reads_max_error_ = false;
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
    // The phase-1 mesh's topology, which conforming splits and merges never change.
    TopologyReport root_topology_;
    bool has_boundary_ = false;  // some edge has one triangle (then splits may add 1)

    std::uint32_t next_vertex_id_ = 0;
    std::uint32_t next_triangle_id_ = 0;
    SlotDeltaLog delta_;
    RefineCounters counters_;
    SplitPlan plan_;  // scratch
    std::vector<std::uint32_t> exchange_merges_;
    std::vector<std::uint32_t> unplannable_;
    std::vector<std::uint32_t> stale_, pending_;
    std::vector<ProjectionRequest> requests_;
    std::vector<Projection> projections_;
    // Projections made ahead of their splits: the split queue's next leaves are almost always
    // the next splits (a split's children have smaller errors, in lower buckets), so their base
    // midpoints are projected in the batch of the one asked for. Each is the projection its
    // split would make (the same request, the same bits), so the results do not change.
    struct AheadProjection {
        std::uint32_t slot = kNone;  // kNone: free
        std::uint32_t id = 0;        // of the triangle in the slot then
        std::uint64_t version = 0;
        std::uint64_t batch = 0;  // ahead_batch_ when made
        Projection projection;
    };
    static constexpr std::size_t kProjectedAhead = 7;
    static constexpr std::uint64_t kAheadBatches = 4;  // an entry's life, in batches
    std::array<AheadProjection, kProjectedAhead> ahead_{};
    std::uint64_t ahead_batch_ = 0;  // batches of projections made
    std::vector<std::uint32_t> ahead_pending_;
    std::vector<TriangleGeometry> geometries_;
    std::vector<double> errors_;
    std::vector<double> midpoint_values_;

    // Refresh after set_field: vertices, then leaves, then mergeable records.
    enum class RefreshStage : std::uint8_t { None, Vertices, Leaves, Records };
    RefreshStage refresh_stage_ = RefreshStage::None;
    std::vector<std::uint32_t> refresh_list_;
    std::size_t refresh_next_ = 0;
    bool refresh_failed_ = false;  // some vertex found no surface since the last set_field
    bool restarted_ = false;       // reset() since the last step
};

}  // namespace isomesh
