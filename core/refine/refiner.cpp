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
#include <stdexcept>
#include <string>
#include <utility>

#include <glm/common.hpp>

#include "mesh/topology.h"
#include "refine/refiner_impl.h"

namespace isomesh {

using namespace refiner_detail;

namespace {

std::unique_ptr<PriorityQueue> make_queue(QueueKind kind, QueueOrder order,
                                          const BucketQueueSettings& buckets) {
    if (kind == QueueKind::Heap) return std::make_unique<HeapQueue>(order);
    return std::make_unique<BucketQueue>(order, buckets);
}

}  // namespace

namespace {

// The checks analyze_topology cannot make, or needs made first (it throws on bad indices).
std::string index_and_value_problem(const Mesh& mesh) {
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
    return {};
}

std::string topology_problem(const TopologyReport& report) {
    if (report.nonmanifold_edges != 0) return "an edge is shared by three or more triangles";
    if (report.inconsistently_oriented_edges != 0)
        return "two triangles disagree on orientation across an edge";
    return {};
}

}  // namespace

RefineCounters& operator+=(RefineCounters& total, const RefineCounters& more) {
    total.splits += more.splits;
    total.merges += more.merges;
    total.swaps += more.swaps;
    total.refreshed_vertices += more.refreshed_vertices;
    total.refreshed_triangles += more.refreshed_triangles;
    total.refused_vertices += more.refused_vertices;
    total.failed_refreshes += more.failed_refreshes;
    total.restarts += more.restarts;
    total.refused_splits += more.refused_splits;
    return total;
}

std::string validate_refinable(const Mesh& mesh) {
    const std::string problem = index_and_value_problem(mesh);
    return problem.empty() ? topology_problem(analyze_topology(mesh)) : problem;
}

Refiner::Impl::Impl(std::shared_ptr<const Field> field, const Mesh& first_mesh,
                    RefineSettings settings)
    : settings_(std::move(settings)),
      constraint_(settings_.constraint),
      constraint_reads_max_error_(constraint_.reads_max_error()) {
    if (!field) throw std::invalid_argument("Refiner: null field");
    if (!settings_.error_measure) settings_.error_measure = std::make_shared<DistanceError>();
    if (!(settings_.swap_ratio > 1.0))
        throw std::invalid_argument("Refiner: swap_ratio must be > 1");
    field_ = std::move(field);
    evaluator_ = field_->make_evaluator();
    next_vertex_id_ = settings_.first_vertex_id;
    next_triangle_id_ = settings_.first_triangle_id;
    split_queue_ = make_queue(settings_.queue, QueueOrder::HighestFirst, settings_.buckets);
    blocked_queue_ = make_queue(settings_.queue, QueueOrder::HighestFirst, settings_.buckets);
    merge_queue_ = make_queue(settings_.queue, QueueOrder::LowestFirst, settings_.buckets);
    load(first_mesh);
    delta_.clear();  // the first mesh is the snapshot, not a change
}

// ---------------------------------------------------------------------------------------------
// Structure

void Refiner::Impl::load(const Mesh& input) {
    std::string problem = index_and_value_problem(input);
    if (problem.empty()) {
        root_topology_ = analyze_topology(input);
        problem = topology_problem(root_topology_);
    }
    if (!problem.empty()) throw std::invalid_argument("Refiner: " + problem);
    Mesh mesh = input;
    build_adjacency(mesh);
    reserve_for(mesh.triangles.size());

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
    const std::vector<ValueGradient> gradients = missing_gradients(mesh);
    for (std::uint32_t v = 0; v < mesh.positions.size(); ++v) {
        if (slot_of[v] == kNone) continue;
        const std::uint32_t slot = vertices_.allocate();
        slot_of[v] = slot;
        Vertex& V = vertices_[slot];
        V.id = next_vertex_id_++;
        V.position = mesh.positions[v];
        V.normal = mesh.normals.empty() ? glm::dvec3(0.0) : mesh.normals[v];
        if (gradients.empty()) {
            V.gradient_norm = mesh.gradient_norms[v];
        } else {
            const glm::dvec3& gradient = gradients[v].gradient;
            if (V.normal == glm::dvec3(0.0) || !finite(V.normal)) V.normal = unit_or_zero(gradient);
            V.gradient_norm = finite(gradient) ? glm::length(gradient) : 0.0;
        }
        V.scale = std::numeric_limits<double>::infinity();
        V.version = version_;
        V.alive = true;
        delta_.add_vertex(V.id, slot);
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
                // A vertex where the surface meets an edge of the box has a boundary edge on
                // each of the two faces: it keeps both coordinates.
                const std::uint8_t axes = face_axes(a.position, b.position, bounds_);
                a.fixed_axes |= axes;
                b.fixed_axes |= axes;
            }
        }
    }
    root_edge_length_ = mesh.triangles.empty() ? 0.0 : edge_sum / (3.0 * mesh.triangles.size());
    ensure_errors(tri_slot);
    for (std::uint32_t slot : tri_slot) add_leaf(slot);
}

std::vector<ValueGradient> Refiner::Impl::missing_gradients(const Mesh& mesh) {
    // Phase 1 found every vertex with the gradient: nothing to evaluate when it passed on the
    // norms and every normal.
    const bool known =
        mesh.gradient_norms.size() == mesh.positions.size() &&
        mesh.normals.size() == mesh.positions.size() &&
        std::all_of(mesh.normals.begin(), mesh.normals.end(),
                    [](const glm::dvec3& n) { return n != glm::dvec3(0.0) && finite(n); });
    if (known) return {};
    std::vector<double> x, y, z;
    for (std::uint32_t v = 0; v < mesh.positions.size(); ++v) {
        x.push_back(mesh.positions[v].x);
        y.push_back(mesh.positions[v].y);
        z.push_back(mesh.positions[v].z);
    }
    std::vector<ValueGradient> gradients(mesh.positions.size());
    evaluator_->value_gradients({x, y, z}, gradients);
    return gradients;
}

void Refiner::Impl::reserve_for(std::size_t root_triangles) {
    // Room for the budget at once where recycled memory holds it (Reservation), within reason (a
    // bound far above what a mesh reaches does not reserve its memory); else for a few times the
    // roots, growing by doubling from there.
    constexpr std::size_t kMostReserved = 500'000;
    constexpr std::size_t kRootGrowth = 4;
    const auto leaves_for = [&](std::size_t budget) {
        return std::min(kMostReserved, std::max(root_triangles, budget));
    };
    const std::size_t budget = constraint_.triangle_limit().value_or(0);
    const std::size_t leaves = leaves_for(budget);
    const std::size_t few = leaves_for(std::min(budget, kRootGrowth * root_triangles));
    const Reservation triangles(2 * leaves + root_triangles, 2 * few + root_triangles);
    const Reservation vertices(leaves / 2 + 3, few / 2 + 3);
    const Reservation records(leaves / 2 + 1, few / 2 + 1);
    triangles_.reserve(triangles);
    vertices_.reserve(vertices);
    records_.reserve(records);
    // Queue handles are triangle and record slots; the delta logs one change per triangle made
    // or removed and per vertex made.
    split_queue_->reserve(triangles);
    blocked_queue_->reserve(triangles);
    merge_queue_->reserve(records);
    delta_.reserve(vertices, {2 * triangles.wanted, 2 * triangles.fallback});
}

void Refiner::Impl::clear_all_into_delta() {
    for (std::uint32_t t = 0; t < triangles_.size(); ++t)
        if (triangles_[t].state == TriangleState::Leaf) delta_.remove_triangle(triangles_[t].id);
    for (std::uint32_t v = 0; v < vertices_.size(); ++v)
        if (vertices_[v].alive) delta_.remove_vertex(vertices_[v].id);
    vertices_.clear();
    triangles_.clear();
    records_.clear();
    ahead_.fill({});
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

MeshDelta Refiner::Impl::take_delta() {
    return delta_.take([this](std::uint32_t v) { return delta_vertex(v); },
                       [this](std::uint32_t t) { return delta_triangle(t); });
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
// Steps and views

StepResult Refiner::Impl::step(const StepBudget& budget, bool take) {
    const RefineCounters before = counters_;
    StepResult result;
    std::size_t operations = 0;
    while (operations < budget.operations) {
        if ((settings_.cancel && settings_.cancel->load(std::memory_order_relaxed)) ||
            budget.work.cancelled()) {
            result.cancelled = true;
            break;
        }
        // A step makes progress whatever its time budget: the first operation is always done.
        if (operations > 0 && budget.work.timed() && budget.work.exhausted()) break;
        if (refresh_pending()) {
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
    result.restarted = std::exchange(restarted_, false);
    result.splits = counters_.splits - before.splits;
    result.merges = counters_.merges - before.merges;
    if (take) result.delta = take_delta();
    return result;
}

MeshStats Refiner::Impl::stats(bool with_max_error) const {
    MeshStats s;
    s.triangles = leaf_count_;
    s.total_error = std::max(0.0, total_error_.value());
    if (with_max_error)
        s.max_error =
            std::max(split_queue_->extreme_priority(), blocked_queue_->extreme_priority());
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

Refiner::~Refiner() = default;

StepResult Refiner::step(const StepBudget& budget) {
    return impl_->step(budget, true);
}

StepResult Refiner::run_to_convergence(std::size_t operations_per_step) {
    StepResult total;
    const StepBudget budget{operations_per_step, WorkBudget{}};
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
bool Refiner::field_change_pending() const {
    return impl_->field_change_pending();
}
std::size_t Refiner::vertices_to_move() const {
    return impl_->vertices_to_move();
}
bool Refiner::refresh_failed() const {
    return impl_->refresh_failed();
}
void Refiner::reset(const Mesh& first_mesh) {
    impl_->reset(first_mesh);
}
std::uint32_t Refiner::next_vertex_id() const {
    return impl_->next_vertex_id();
}
std::uint32_t Refiner::next_triangle_id() const {
    return impl_->next_triangle_id();
}
const TopologyReport& Refiner::root_topology() const {
    return impl_->root_topology();
}
std::size_t Refiner::inverted_triangles() const {
    return impl_->inverted_triangles();
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
