// Phase 2: progressive refinement of a phase-1 mesh (the thesis, chapter 3.2 and 3.3.3: ROAM on
// the dual graph of a Marching Cubes mesh), with the parts the thesis left out: merges, changing
// constraints and changing functions.
//
// A Refiner owns one surface's refinement state and is used by one thread at a time (a server
// runs many refiners on a worker pool). Each call to step() performs whole operations until its
// budget is spent or there is nothing left to do, and returns the net change as a MeshDelta.
//
// Operations (see refiner.cpp for the algorithms and the papers):
// - split: bisect a triangle's base edge at its midpoint projected onto the surface; the triangle
//   across the base edge is bisected with it, after forced splits when its own base edge differs
//   (ROAM's forced splits), so the mesh stays conforming: no T-junctions, watertight if it was.
//   Base edges: the longest edge for phase-1 triangles (thesis 3.3.2); a child's base edge is the
//   side it keeps from its parent (ROAM's bintree rule, newest vertex bisection), which makes the
//   number of triangles a split creates known before it is made.
// - merge: undo a split whose children are all unsplit; every phase-1 triangle is the root of its
//   own tree of splits (the thesis's "multi-rooted tree", 3.2.3).
// - refresh: after set_field, move every vertex onto the new surface and re-prioritise (in
//   batches of evaluations);
// - reset: start again from another mesh (a new phase-1 mesh: progressive/pipeline.h decides when
//   the topology changed), with ids continuing so that the delta replaces everything.
// The split queue orders unsplit triangles by error, largest first; the merge queue orders
// mergeable splits by the larger error of the triangles a merge restores, smallest first (ROAM's
// dual queues). While the constraint wants refinement the best split that does not overshoot it is
// made; while the mesh would still satisfy it after a merge (or is over a triangle budget) the
// best merge is made; otherwise the cheapest merges are exchanged for a split worth swap_ratio
// times more than each. The mesh is then optimal for the constraint in ROAM's sense, up to that
// hysteresis (see queue_ends).
//
// Exceptions thrown by the field's evaluator pass through step(); the refiner may then be in the
// middle of an operation and must be discarded.
//
// Determinism: the operation sequence depends only on the input mesh, the function, the settings
// and the sequence of calls (set_constraint, set_field), never on how operation-count budgets cut
// it into steps. Time budgets are not deterministic by nature.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "eval/evaluator.h"
#include "mesh/mesh.h"
#include "mesh/topology.h"
#include "refine/constraints.h"
#include "refine/error_measures.h"
#include "refine/mesh_delta.h"
#include "refine/split_queue.h"
#include "refine/surface_projection.h"
#include "work/work_budget.h"

namespace isomesh {

/// The octree depth phase 1 starts from when its mesh is to be refined: coarser than for phase 1
/// alone, since refinement spends triangles better than a uniform octree level
/// (tests/refine/accuracy_test). The server and the CLI both use it, so their meshes match.
inline constexpr int kRefinePhase1MinDepth = 3;

struct RefineSettings {
    /// The split priority; nullptr means "distance" (see error_measures.h for why).
    std::shared_ptr<const ErrorMeasure> error_measure;
    /// When to stop; can be changed later with set_constraint. The default never refines.
    Constraint constraint;
    QueueKind queue = QueueKind::Bucket;
    BucketQueueSettings buckets;
    ProjectionSettings projection;
    /// A split and a merge are exchanged when the split's priority exceeds the merge's by this
    /// factor (> 1; hysteresis against exchanging back and forth).
    double swap_ratio = 1.1;
    /// Triangles with an edge shorter than this are never split (nor forced to split).
    double min_edge_length = 1e-7;
    /// A bound on forced splits per split (never reached on meshes whose base edges are longest
    /// edges; a guard against malformed input).
    std::size_t max_forced_chain = 4096;
    /// The first vertex and triangle ids this refiner gives (a refiner that takes over from
    /// another one starts after that one's ids, so a client can hold both meshes' ids apart).
    std::uint32_t first_vertex_id = 0;
    std::uint32_t first_triangle_id = 0;
    /// The meshing box: a split whose new vertex would land outside it (the surface bulging out
    /// past a face the mesh ends on) is not made, nor one whose projection onto the surface
    /// fails; the triangle stays as it is until the function changes. Infinite by default.
    Box box{glm::dvec3(-std::numeric_limits<double>::infinity()),
            glm::dvec3(std::numeric_limits<double>::infinity())};
    /// Checked between operations; step() returns early when it becomes true.
    const std::atomic<bool>* cancel = nullptr;
};

struct StepBudget {
    StepBudget() = default;
    StepBudget(std::size_t operations_, WorkBudget work_ = {})
        : operations(operations_), work(std::move(work_)) {}

    /// Operations: bisections (a forced chain is not cut: the last split may exceed the budget),
    /// merges, and vertices or triangles refreshed after a function change.
    std::size_t operations = 1024;
    /// Time and cancellation, checked between operations after the first (a step makes progress
    /// whatever its time). Time limits are not deterministic.
    WorkBudget work;
};

struct StepResult {
    MeshDelta delta;
    std::size_t splits = 0;  // bisections, forced ones included
    std::size_t merges = 0;
    std::size_t refreshed = 0;  // vertices and triangles updated for a new function
    bool restarted = false;     // the mesh was replaced (reset): the delta removes every triangle
    bool converged = false;     // nothing left to do until the constraint or function changes
    bool cancelled = false;
};

/// Counters over the refiner's life.
struct RefineCounters {
    std::size_t splits = 0;
    std::size_t merges = 0;
    std::size_t swaps = 0;
    std::size_t refreshed_vertices = 0;
    std::size_t refreshed_triangles = 0;
    std::size_t refused_vertices = 0;  // splits refused: no valid vertex (on the surface, in the
                                       // box, folding nothing) for them
    std::size_t failed_refreshes = 0;  // vertices that found no surface nearby after set_field
    std::size_t restarts = 0;
    std::size_t refused_splits = 0;  // chains longer than max_forced_chain
};

/// Sums counters (of several refiners in turn).
RefineCounters& operator+=(RefineCounters& total, const RefineCounters& more);

/// The ends of the two queues: the largest split priority (splittable leaves) and the smallest
/// merge priority (0 when a queue is empty). Converged under a triangle budget, the refiner leaves
/// no split that fits worth more than swap_ratio times the cheapest merge (ROAM's optimality, up to
/// the hysteresis).
struct QueueEnds {
    double largest_split = 0.0;
    double smallest_merge = 0.0;
};

/// The current mesh in compact form, triangles and vertices sorted by id.
struct RefinedMesh {
    Mesh mesh;  // with neighbours and base_edge
    std::vector<std::uint32_t> triangle_ids;
    std::vector<std::uint32_t> vertex_ids;
};

/// Empty when `mesh` can be refined, else why not: indices out of range, non-finite positions,
/// a triangle with a repeated vertex, an edge shared by three or more triangles, or two triangles
/// disagreeing on orientation across an edge.
std::string validate_refinable(const Mesh& mesh);

class Refiner {
  public:
    /// Starts from `first_mesh` (phase 1's output; its neighbours and base_edge are recomputed).
    /// Throws std::invalid_argument when validate_refinable fails or field is null.
    /// The starting mesh is snapshot() right after construction.
    Refiner(std::shared_ptr<const Field> field, const Mesh& first_mesh, RefineSettings settings);
    ~Refiner();
    Refiner(const Refiner&) = delete;
    Refiner& operator=(const Refiner&) = delete;

    StepResult step(const StepBudget& budget);
    /// Steps until converged or cancelled (`operations_per_step` operations at a time); returns
    /// the merged delta. Precondition: the constraint can be met (an error bound alone on a
    /// surface with a singularity may refine until memory runs out: add a triangle budget).
    StepResult run_to_convergence(std::size_t operations_per_step = 4096);

    void set_constraint(Constraint constraint);
    const Constraint& constraint() const;

    /// A new version of the function (new parameter values or a new tape). Vertices move onto the
    /// new surface during the following steps, coarse before fine; then the queues re-converge.
    /// Whether the topology stayed the same is not the refiner's to know: its owner compares a
    /// fresh phase-1 mesh with root_topology() and calls reset() (progressive/pipeline.h).
    /// Throws on a null field.
    void set_field(std::shared_ptr<const Field> field);
    std::uint64_t version() const;
    /// True from set_field until step() has moved every vertex onto the new surface and updated
    /// every error: until then the mesh mixes versions.
    bool field_change_pending() const;
    /// After set_field, the vertices step() has yet to move onto the new surface (each is one
    /// operation); 0 once every vertex moved. The errors are refreshed after: from then on the
    /// mesh no longer mixes versions, but nothing is split or merged until field_change_pending()
    /// is false.
    std::size_t vertices_to_move() const;
    /// Since the last set_field, some vertex found no surface within its reach (it stayed where it
    /// was): the mesh does not follow the new function there.
    bool refresh_failed() const;
    /// Starts again from `first_mesh` (as the constructor, for the current field, constraint and
    /// version): the next step's delta removes every triangle and adds the new mesh, whose ids
    /// continue after the old ones. Throws std::invalid_argument when validate_refinable fails.
    void reset(const Mesh& first_mesh);
    /// The ids the next new vertex and triangle will get.
    std::uint32_t next_vertex_id() const;
    std::uint32_t next_triangle_id() const;
    /// The topology of the current mesh: its phase-1 mesh's, which splits and merges keep.
    const TopologyReport& root_topology() const;
    /// Leaves facing against the surface: their geometric normal points away from the mean of
    /// their corners' normals (a fold left by moving vertices onto a new surface).
    std::size_t inverted_triangles() const;

    MeshStats stats() const;
    QueueEnds queue_ends() const;
    const RefineCounters& counters() const;
    RefinedMesh mesh() const;
    /// The delta that builds the current mesh from nothing.
    MeshDelta snapshot() const;

  private:
    class Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace isomesh
