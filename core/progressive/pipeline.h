// The progressive mesher: the one way to turn a function into a mesh that sharpens over time,
// used by the server, the CLI, the benchmarks and the tests.
//
//   phase 1, anytime (polygonize/polygonizer.h)  ->  simplification to the triangle budget
//   (mesh/simplify.h), when phase 1's mesh is larger  ->  refinement (refine/refiner.h)
//
// The first step makes a mesh within its budget whatever the function: octree cells are
// classified for part of the budget, largest first, and the frontier reached is meshed. Later
// steps go on classifying; the mesh is made again each time the work done has doubled (and at
// least min_intermediate_interval of it went by), of the frontier coarsened to max_preview_cells
// (a preview), and once more when every cell is classified (the mesh with the topology
// guarantee, of the whole frontier). Each such mesh
// replaces the whole mesh (the step's delta removes every triangle and adds the new ones:
// `restarted`). From then on the refiner splits and merges until the constraint is met.
//
// The triangle budget is a bound at every step: a phase-1 mesh over it is simplified below it
// (simplify_share) with topology-preserving collapses first (after the first mesh, over as many
// steps as that takes, the mesh shown so far staying until then: no step runs for seconds), and
// the refiner's splits spend the rest by error. Where no mesh of that
// topology fits (a surface with more components or handles than the budget has triangles for), the
// mesh is the smallest those collapses reach, and status().budget_unreachable says so.
//
// A new version of the function (set_field) moves the vertices onto the new surface at once (a
// slider's surface glides), while phase 1 runs again for the new function; when it is done, the
// moved mesh is kept if it has the new surface's topology and no triangle folded over, otherwise
// the new phase-1 mesh replaces it. A vertex that finds no surface in reach shows the new phase
// 1's mesh as soon as it has one. A kept mesh is refined until it converges; then the new phase-1
// mesh is refined aside (no frames) and replaces it once converged, so that a version's final
// mesh is the one a new pipeline makes of it, whatever came before (a server rebuilding a session
// from its definition gets the same mesh).
//
// Determinism: the mesh once converged depends only on the function, the settings and the
// sequence of calls, not on how budgets cut the work into steps, nor on the number of threads.
// What intermediate steps show depends on the time they were given.
#pragma once

#include <atomic>
#include <cstddef>
#include <memory>
#include <optional>

#include "mesh/mesh.h"
#include "mesh/simplify.h"
#include "mesh/topology.h"
#include "polygonize/polygonizer.h"
#include "refine/refiner.h"
#include "work/work_budget.h"

namespace isomesh {

/// Phase 1 as refinement wants it: coarser than for phase 1 alone (refinement spends triangles
/// better than a uniform octree level: tests/refine/accuracy_test), one thread by default.
PolygonizeSettings refinement_phase1_settings();

struct PipelineSettings {
    /// The box, depths, threads, helpers and cell cap of phase 1 (its cancel flag is not read: the
    /// step budget's is).
    PolygonizeSettings phase1 = refinement_phase1_settings();
    /// The error measure, constraint (budget and error bound), queue and projection of the
    /// refiner (its cancel flag is not read: the step budget's is).
    RefineSettings refine;
    /// Of the first step's budget, the share spent classifying octree cells; the rest meshes
    /// them. In (0, 1].
    double first_mesh_share = 0.4;
    /// The first mesh is made of at most about this many octree cells (meshing costs a few
    /// microseconds a cell): the first step stops classifying there even if time is left.
    std::size_t first_mesh_cells = 512;
    /// Intermediate phase-1 meshes are made only while the octree has at most this many cells
    /// (beyond, meshing them costs more than it shows; the final mesh is always made).
    std::size_t max_intermediate_cells = 50'000;
    /// And only after this much of the step budgets' time (their clock's units: microseconds of
    /// CPU time in the server) went into phase 1 since the last phase-1 mesh. Each is a keyframe of
    /// the whole mesh: a phase 1 that resolves within a fraction of a second shows its first mesh
    /// and its final one, not three previews a few tens of milliseconds apart (the gyroid's cost
    /// 86 kB, a third of its stream at 100,000 triangles); a slow one shows a new mesh at most
    /// about four times a second.
    std::int64_t min_intermediate_interval = 250'000;
    /// An intermediate mesh is made of the octree's frontier coarsened to at most this many cells
    /// (polygonize/octree.h: coarsened): its cost is bounded by it, whatever the octree holds.
    /// Shown simplified to simplify_share of the budget (5,000 triangles at the server's default
    /// 20,000), a finer one shows little more: bear.vm's at depth 3..7 was of 53,128 cells
    /// (depth 7, 34,644 triangles) and cost 356 ms of its 2.1 s phase 1 (meshing it, then
    /// simplifying it); coarsened, of 11,287 cells (depth 6, 11,714 triangles), its phase 1 is
    /// 13% shorter.
    std::size_t max_preview_cells = 25'000;
    /// A phase-1 mesh over the triangle budget is simplified to this share of it (where its
    /// topology allows), and the refiner's splits spend the rest by error. In [0, 1]. A quarter:
    /// at 20,000 triangles (bench_pipeline, rms distance to the surface, share 0.1 / 0.25 / 0.5)
    /// colonnade.vm 6.7e-4 / 4.8e-4 / 5.7e-4, bear.vm 3.8e-4 / 3.5e-4 / 3.5e-4, the heart
    /// - / 2.3e-4 / 2.5e-4, the genus-2 surface - / 1.6e-4 / 1.7e-4: below a quarter the
    /// collapses coarsen what the splits then fail to bring back.
    double simplify_share = 0.25;
};

/// Where the mesh stands.
struct PipelineStatus {
    /// Phase 1 still classifies cells: a later step may replace the mesh.
    bool resolving = true;
    /// Octree cells of the last phase-1 mesh meshed without the topology guarantee (not yet
    /// classified, or unproven at the deepest level: a singular point, a crease).
    std::size_t unresolved_cells = 0;
    /// Phase 1 is done and every cell met the leaf conditions: the mesh has the surface's
    /// topology.
    bool certified = false;
    /// f is zero on a whole region of the box: the equation holds there, which is no surface;
    /// the mesh is empty and phase 1 stopped at once.
    bool region = false;
    /// The phase-1 mesh could not be simplified to the triangle budget without changing its
    /// topology: the mesh has minimum_triangles triangles, the fewest the collapses reached.
    bool budget_unreachable = false;
    std::size_t minimum_triangles = 0;
    /// Phase-1 meshes made so far (each replaced the mesh).
    std::size_t phase1_meshes = 0;
};

struct PipelineStep {
    /// The changes since the last step (ids as the refiner's: refiner.h, mesh_delta.h).
    MeshDelta delta;
    /// The delta replaces the whole mesh (a phase-1 mesh was installed).
    bool restarted = false;
    /// Nothing left to do until the function or the constraint changes.
    bool converged = false;
    bool cancelled = false;
    std::size_t splits = 0;
    std::size_t merges = 0;
};

class Pipeline {
  public:
    /// Throws std::invalid_argument for a null field or invalid settings. No work is done until
    /// the first step.
    Pipeline(std::shared_ptr<const Field> field, PipelineSettings settings);
    ~Pipeline();
    Pipeline(const Pipeline&) = delete;
    Pipeline& operator=(const Pipeline&) = delete;

    /// Works until the budget is exhausted or cancelled, or converged. The first step always
    /// returns a mesh (possibly empty: no surface in the box, or none found yet). Exceptions from
    /// the field's evaluators pass through; the pipeline must then be discarded.
    PipelineStep step(const WorkBudget& budget);
    /// Steps until converged or cancelled; returns the merged delta.
    PipelineStep run_to_convergence(const WorkBudget& budget = {});

    /// A new version of the function (see the file comment). Throws on a null field.
    void set_field(std::shared_ptr<const Field> field);
    /// Stops phase 1 for good (a time limit): cells not yet classified count as unresolved, and
    /// the next step makes the final phase-1 mesh of the octree as it stands.
    void settle();
    /// A new constraint; a lower triangle budget simplifies the phase-1 mesh again if needed.
    void set_constraint(Constraint constraint);
    const Constraint& constraint() const { return settings_.refine.constraint; }

    /// The first step was made: there is a mesh.
    bool started() const { return refiner_ != nullptr; }
    /// True from set_field until every vertex moved onto the new surface, or, where some found
    /// no surface in reach, until the new function's first mesh replaced them: until then the
    /// mesh mixes versions.
    bool field_change_pending() const;
    const PipelineStatus& status() const { return status_; }
    /// Precondition for the views below: started().
    MeshStats stats() const;
    /// Over every refiner the pipeline had (a replacement starts a new one).
    RefineCounters counters() const;
    RefinedMesh mesh() const;
    MeshDelta snapshot() const;
    /// Statistics of the last phase-1 mesh made.
    const PolygonizeStats& phase1_stats() const { return phase1_stats_; }

  private:
    void first_mesh(const WorkBudget& budget);
    void advance_phase1(const WorkBudget& budget);
    void finish_phase1(const WorkBudget& budget);
    void continue_intermediate(const WorkBudget& budget);
    PolygonizeSettings phase1_settings() const;
    PolygonizeResult phase1_mesh(const WorkBudget& budget);
    void record_phase1_mesh(const PolygonizeResult& result);
    /// Makes `mesh` (a phase-1 mesh) the refiner's roots, simplified below the budget first where
    /// it is over it: at once, or (`sliced`) over this and the next steps, the refiner showing
    /// its mesh until then.
    void install(Mesh mesh, const WorkBudget& budget, bool sliced = false);
    /// Goes on with the simplification install() started; true once the roots are installed.
    bool continue_install(const WorkBudget& budget);
    void set_roots(Mesh root);
    Mesh fit_to_budget(Mesh mesh, const WorkBudget& budget);
    /// The budget, and simplify_share of it where the topology allows.
    SimplifyTarget simplify_target() const;
    void record_simplification(const SimplifyReport& report);
    bool keeps_moved_mesh(const Mesh& fresh) const;
    void refine(PipelineStep& out, const StepBudget& budget);
    void move_vertices(PipelineStep& out, const WorkBudget& budget);
    /// Every vertex had its turn to move and some found no surface in reach.
    bool moved_mesh_failed() const;
    void replace_moved_mesh(const WorkBudget& budget);
    void settle_version(PipelineStep& out, const WorkBudget& budget);
    void retire_refiner();

    std::shared_ptr<const Field> field_;
    PipelineSettings settings_;
    std::unique_ptr<Polygonizer> phase1_;  // null once phase 1 is done
    std::unique_ptr<Refiner> refiner_;
    // The new version's own phase-1 mesh refined aside while a kept moved mesh is shown.
    std::unique_ptr<Refiner> shadow_;
    bool canonical_pending_ = false;  // installed_ is to replace a kept moved mesh
    RefineCounters retired_counters_;
    std::optional<Mesh> installed_;  // the last phase-1 mesh installed, before simplification
    std::unique_ptr<Simplification> simplifying_;  // installed_ on its way to the refiner
    std::optional<PolygonizeResult> final_mesh_;   // phase 1's, made, to install next step
    bool intermediate_ = false;  // an intermediate phase-1 mesh is being made (mesh_slice)
    std::size_t classified_at_last_mesh_ = 0;
    /// Budget units spent in phase-1 steps since the last phase-1 mesh.
    std::int64_t phase1_work_since_mesh_ = 0;
    bool field_changing_ = false;  // set_field: phase 1 of the new function decides the topology
    PipelineStatus status_;
    PolygonizeStats phase1_stats_;
};

}  // namespace isomesh
