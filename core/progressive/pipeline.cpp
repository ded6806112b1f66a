// The progressive mesher (see pipeline.h).
#include "progressive/pipeline.h"

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <utility>

#include "mesh/simplify.h"

namespace isomesh {
namespace {

/// An intermediate phase-1 mesh is made when the cells classified have doubled since the last.
constexpr double kRemeshGrowth = 2.0;
/// Of a step's budget, the share that moves vertices onto a new surface before phase 1 runs.
constexpr double kRefreshShare = 0.5;
constexpr std::size_t kAllOperations = ~std::size_t{0};

/// The same vertices (positions and normals) and triangles, in the same order.
bool same_geometry(const Mesh& a, const Mesh& b) {
    return a.triangles == b.triangles && a.positions == b.positions && a.normals == b.normals;
}

bool same_topology(const TopologyReport& a, const TopologyReport& b) {
    return a.components == b.components && a.euler_characteristic == b.euler_characteristic &&
           (a.boundary_edges == 0) == (b.boundary_edges == 0);
}

void gather(MeshDelta& into, MeshDelta delta) {
    if (into.empty()) {
        into = std::move(delta);
        return;
    }
    DeltaBuilder builder;
    for (const MeshDelta* d : {&into, &delta}) {
        for (std::uint32_t id : d->removed_triangles) builder.remove_triangle(id);
        for (std::uint32_t id : d->removed_vertices) builder.remove_vertex(id);
        for (const DeltaVertex& v : d->added_vertices) builder.add_vertex(v);
        for (const DeltaVertex& v : d->moved_vertices) builder.move_vertex(v);
        for (const DeltaTriangle& t : d->added_triangles) builder.add_triangle(t);
    }
    into = builder.take();
}

}  // namespace

PolygonizeSettings refinement_phase1_settings() {
    PolygonizeSettings s;
    s.min_depth = kRefinePhase1MinDepth;
    s.threads = 1;
    return s;
}

Pipeline::Pipeline(std::shared_ptr<const Field> field, PipelineSettings settings)
    : field_(std::move(field)), settings_(std::move(settings)) {
    if (!field_) throw std::invalid_argument("Pipeline: null field");
    if (!(settings_.first_mesh_share > 0.0 && settings_.first_mesh_share <= 1.0))
        throw std::invalid_argument("Pipeline: first_mesh_share must be in (0, 1]");
    settings_.phase1.cancel = nullptr;
    settings_.refine.cancel = nullptr;
    settings_.refine.box = settings_.phase1.box;
    phase1_ = std::make_unique<Polygonizer>(field_, phase1_settings());
}

Pipeline::~Pipeline() = default;

PipelineStep Pipeline::step(const WorkBudget& budget) {
    PipelineStep out;
    if (simplifying_) {
        // A large phase-1 mesh on its way to the budget: nothing else moves meanwhile.
        if (continue_install(budget) && !phase1_ && !budget.exhausted())
            refine(out, {kAllOperations, budget});
        refine(out, {0, budget});
        out.cancelled = budget.cancelled();
        return out;
    }
    const bool first = !refiner_;
    const bool resolving = phase1_ != nullptr;
    if (first) {
        first_mesh(budget);
    } else if (refiner_->vertices_to_move() > 0) {
        move_vertices(out, budget);
    } else if (moved_mesh_failed()) {
        replace_moved_mesh(budget);
    } else if (phase1_) {
        if (refiner_->field_change_pending())
            refine(out, {kAllOperations, budget.portion(kRefreshShare)});
        advance_phase1(budget);
    } else if (shadow_) {
        settle_version(out, budget);
    } else {
        refine(out, {kAllOperations, budget});
        if (out.converged && canonical_pending_) settle_version(out, budget);
    }
    // Phase 1 just ended: refine with what the step has left, so that a mesh already meeting the
    // constraint leaves flagged converged. Not in the first step, whose mesh leaves at once: one
    // operation there tells whether the constraint is met already.
    if (refiner_ && resolving && !phase1_ && !simplifying_ && !budget.exhausted()) {
        refine(out, {first ? std::size_t{1} : kAllOperations, budget});
        // A kept moved mesh that converged makes way for the version's own mesh first.
        if (out.converged && canonical_pending_) settle_version(out, budget);
    }
    if (refiner_ && first) {
        out.delta = refiner_->snapshot();
        out.restarted = true;
    } else if (refiner_) {
        refine(out, {0, budget});  // what the refiner holds back: a reset's replacement
    }
    out.cancelled = budget.cancelled();
    return out;
}

void Pipeline::move_vertices(PipelineStep& out, const WorkBudget& budget) {
    // The moved mesh is what a viewer of a new version waits for: the vertices get the whole
    // step, which ends once they are all moved (one operation each) so that the frame leaves at
    // once; phase 1 of the new function and the errors' refresh follow in the next steps.
    refine(out, {refiner_->vertices_to_move(), budget});
}

bool Pipeline::moved_mesh_failed() const {
    return field_changing_ && refiner_->vertices_to_move() == 0 && refiner_->refresh_failed();
}

void Pipeline::replace_moved_mesh(const WorkBudget& budget) {
    // Some vertex found no surface within its reach and stayed where it was: the moved mesh does
    // not follow the new surface (a slider that jumped far). The new function's first mesh
    // replaces it, made as a session's first is, in a step of its own: the move may have used up
    // the step before, and phase 1 given no time meshes nothing (an empty surface, shown).
    field_changing_ = false;
    first_mesh(budget);
}

void Pipeline::refine(PipelineStep& out, const StepBudget& budget) {
    StepResult r = refiner_->step(budget);
    gather(out.delta, std::move(r.delta));
    out.restarted = out.restarted || r.restarted;
    out.splits += r.splits;
    out.merges += r.merges;
    if (budget.operations > 0) out.converged = r.converged && !phase1_;
}

PipelineStep Pipeline::run_to_convergence(const WorkBudget& budget) {
    PipelineStep total;
    for (;;) {
        PipelineStep s = step(budget);
        gather(total.delta, std::move(s.delta));
        total.restarted = total.restarted || s.restarted;
        total.splits += s.splits;
        total.merges += s.merges;
        if (s.converged || s.cancelled || budget.exhausted()) {
            total.converged = s.converged;
            total.cancelled = s.cancelled;
            return total;
        }
    }
}

void Pipeline::settle_version(PipelineStep& out, const WorkBudget& budget) {
    out.converged = false;
    if (!shadow_) {
        RefineSettings settings = settings_.refine;
        settings.first_vertex_id = refiner_->next_vertex_id();
        settings.first_triangle_id = refiner_->next_triangle_id();
        shadow_ = std::make_unique<Refiner>(field_, fit_to_budget(*installed_, budget), settings);
    }
    if (!shadow_->step({kAllOperations, budget}).converged) return;
    // The swap: every triangle and vertex of the kept mesh out, the new version's own mesh in.
    const MeshDelta old = refiner_->snapshot();
    MeshDelta swap = shadow_->snapshot();
    for (const DeltaTriangle& t : old.added_triangles) swap.removed_triangles.push_back(t.id);
    for (const DeltaVertex& v : old.added_vertices) swap.removed_vertices.push_back(v.id);
    retire_refiner();
    refiner_ = std::move(shadow_);
    canonical_pending_ = false;
    // After what this step already changed (its refinement converged the kept mesh): the swap
    // removes those changes too.
    gather(out.delta, std::move(swap));
    out.restarted = true;
    out.converged = true;
}

void Pipeline::retire_refiner() {
    retired_counters_ += refiner_->counters();
    ++retired_counters_.restarts;  // the replacement
}

void Pipeline::first_mesh(const WorkBudget& budget) {
    phase1_->advance(budget.portion(settings_.first_mesh_share), settings_.first_mesh_cells);
    if (phase1_->complete()) {
        finish_phase1(budget);
        return;
    }
    PolygonizeResult result = phase1_mesh(budget);
    install(std::move(result.mesh), budget);
}

void Pipeline::advance_phase1(const WorkBudget& budget) {
    if (intermediate_) {
        continue_intermediate(budget);
        return;
    }
    phase1_->advance(budget);
    if (phase1_->complete()) {
        finish_phase1(budget);
        return;
    }
    phase1_work_since_mesh_ += budget.elapsed();
    const OctreeCounts& counts = phase1_->counts();
    const bool grown = static_cast<double>(counts.classified) >=
                       kRemeshGrowth * static_cast<double>(classified_at_last_mesh_);
    const bool due = phase1_work_since_mesh_ >= settings_.min_intermediate_interval;
    if (!field_changing_ && grown && due &&
        counts.pending + counts.leaves + counts.unresolved <= settings_.max_intermediate_cells) {
        intermediate_ = true;
        continue_intermediate(budget);
    }
}

void Pipeline::continue_intermediate(const WorkBudget& budget) {
    // Classification waits meanwhile: the mesh is of the octree as it stood.
    std::optional<PolygonizeResult> made = phase1_->mesh_slice(budget, settings_.max_preview_cells);
    if (!made) {
        if (budget.cancelled()) intermediate_ = false;
        return;
    }
    intermediate_ = false;
    record_phase1_mesh(*made);
    install(std::move(made->mesh), budget, true);
}

void Pipeline::finish_phase1(const WorkBudget& budget) {
    if (field_changing_ && refiner_->field_change_pending()) return;  // decide once moved
    // The final mesh can take seconds: made over as many steps as it needs (but the first
    // step's mesh is made in it).
    if (!final_mesh_) {
        final_mesh_ = phase1_->mesh_slice(refiner_ ? budget : WorkBudget(budget.cancel_flag()));
        if (!final_mesh_ || budget.cancelled()) return;
        record_phase1_mesh(*final_mesh_);
        if (refiner_ && budget.exhausted()) return;  // installed at the next step
    }
    PolygonizeResult result = std::move(*final_mesh_);
    final_mesh_.reset();
    status_.resolving = false;
    status_.region = result.stats.region_cells > 0;
    status_.certified = result.stats.certified();
    phase1_.reset();
    // Pending cells of the last intermediate mesh that became leaves unsplit are meshed the same:
    // the final mesh is often the one shown. Installed again it was a second keyframe of the same
    // mesh and a reset of its refinement.
    if (!field_changing_ && installed_ && same_geometry(*installed_, result.mesh)) return;
    if (field_changing_ && keeps_moved_mesh(result.mesh)) {
        field_changing_ = false;
        installed_ = std::move(result.mesh);  // refined aside once the moved mesh converged
        canonical_pending_ = true;
        return;
    }
    field_changing_ = false;
    install(std::move(result.mesh), budget, true);
}

PolygonizeSettings Pipeline::phase1_settings() const {
    PolygonizeSettings s = settings_.phase1;
    s.adjacency = false;  // built once the mesh is at the budget (continue_install)
    return s;
}

PolygonizeResult Pipeline::phase1_mesh(const WorkBudget& budget) {
    PolygonizeResult result = phase1_->mesh(budget);
    record_phase1_mesh(result);
    return result;
}

void Pipeline::record_phase1_mesh(const PolygonizeResult& result) {
    classified_at_last_mesh_ = phase1_->counts().classified;
    phase1_work_since_mesh_ = 0;
    phase1_stats_ = result.stats;
    status_.unresolved_cells = result.stats.unresolved_cells;
    status_.region = result.stats.region_cells > 0;
    ++status_.phase1_meshes;
}

bool Pipeline::keeps_moved_mesh(const Mesh& fresh) const {
    return !refiner_->refresh_failed() && refiner_->inverted_triangles() == 0 &&
           same_topology(analyze_topology(fresh), refiner_->root_topology());
}

// Collapses alone leave the coarse parts of a phase-1 mesh as they were; simplified below the
// budget, the refiner's error-driven splits place the rest where the surface needs them (bear.vm
// at 20,000: error_max 1.4e-3 -> 1.7e-4; the heart 7.2e-3 -> 4.8e-5). Where the topology alone
// needs more than the share (the blobby cube's 983 components), the mesh at the budget is kept
// (SimplifyTarget): collapsing on to the topology's floor only coarsens the small parts, which
// splits never reach.
SimplifyTarget Pipeline::simplify_target() const {
    const double share = std::clamp(settings_.simplify_share, 0.0, 1.0);
    const std::size_t limit = settings_.refine.constraint.triangle_limit().value_or(SIZE_MAX);
    const auto preferred = static_cast<std::size_t>(static_cast<double>(limit) * share);
    return {limit, std::max<std::size_t>(1, preferred)};
}

void Pipeline::record_simplification(const SimplifyReport& report) {
    status_.budget_unreachable = !report.reached && !report.cancelled;
    status_.minimum_triangles = status_.budget_unreachable ? report.triangles : 0;
}

Mesh Pipeline::fit_to_budget(Mesh mesh, const WorkBudget& budget) {
    // Not cut short by the step's time: a mesh over the budget may not be shown.
    const WorkBudget whole(budget.cancel_flag());
    record_simplification(
        simplify_to_budget(mesh, box_faces(mesh, settings_.phase1.box), simplify_target(), whole));
    if (mesh.neighbours.empty()) build_adjacency(mesh);  // phase 1 leaves it to us
    return mesh;
}

void Pipeline::install(Mesh mesh, const WorkBudget& budget, bool sliced) {
    if (budget.cancelled()) return;
    shadow_.reset();
    canonical_pending_ = false;
    installed_ = mesh;
    std::vector<std::uint8_t> faces = box_faces(mesh, settings_.phase1.box);
    simplifying_ =
        std::make_unique<Simplification>(std::move(mesh), std::move(faces), simplify_target());
    // The first mesh must be there after the first step; a later one may take several.
    continue_install(sliced && refiner_ ? budget : WorkBudget(budget.cancel_flag()));
}

bool Pipeline::continue_install(const WorkBudget& budget) {
    if (!simplifying_->advance(budget)) {
        if (budget.cancelled()) simplifying_.reset();
        return false;
    }
    record_simplification(simplifying_->report());
    Mesh root = simplifying_->take();
    simplifying_.reset();
    if (root.neighbours.empty()) build_adjacency(root);  // simplified: compacted
    set_roots(std::move(root));
    return true;
}

void Pipeline::set_roots(Mesh root) {
    if (!refiner_) {
        refiner_ = std::make_unique<Refiner>(field_, root, settings_.refine);
    } else {
        refiner_->reset(root);
    }
}

void Pipeline::set_field(std::shared_ptr<const Field> field) {
    if (!field) throw std::invalid_argument("Pipeline::set_field: null field");
    field_ = std::move(field);
    phase1_ = std::make_unique<Polygonizer>(field_, phase1_settings());
    final_mesh_.reset();
    intermediate_ = false;
    shadow_.reset();
    simplifying_.reset();
    canonical_pending_ = false;
    classified_at_last_mesh_ = 0;
    phase1_work_since_mesh_ = 0;
    status_.resolving = true;
    status_.certified = false;
    status_.region = false;
    if (refiner_) {
        refiner_->set_field(field_);
        field_changing_ = true;
    }
}

void Pipeline::set_constraint(Constraint constraint) {
    settings_.refine.constraint = std::move(constraint);
    shadow_.reset();  // made again for the new constraint once the shown mesh converges
    if (!refiner_) return;
    refiner_->set_constraint(settings_.refine.constraint);
    // A budget below the phase-1 mesh's (simplified) triangles: simplify it again. (A higher one
    // is reached by refining from the roots as they are.)
    const std::optional<std::size_t> limit = settings_.refine.constraint.triangle_limit();
    if (installed_ && (simplifying_ || (limit && refiner_->root_topology().triangles > *limit))) {
        if (field_changing_) {
            // installed_ is the previous version's mesh, off the new surface: show the new
            // version's phase 1 as it stands instead.
            field_changing_ = false;
            intermediate_ = false;
            install(phase1_mesh(WorkBudget{}).mesh, WorkBudget{});
            return;
        }
        install(*installed_, WorkBudget{});
        return;
    }
    // The roots fit the new budget (or there is none): whatever an earlier, lower budget could
    // not reach no longer applies.
    status_.budget_unreachable = false;
    status_.minimum_triangles = 0;
}

void Pipeline::settle() {
    if (phase1_) phase1_->settle();
}

bool Pipeline::field_change_pending() const {
    // The vertices alone: the errors refreshed after them change no triangle a frame shows. A
    // move that failed waits for its replacement (the next step).
    return refiner_ && (refiner_->vertices_to_move() > 0 || moved_mesh_failed());
}

MeshStats Pipeline::stats() const {
    return refiner_->stats();
}

RefineCounters Pipeline::counters() const {
    RefineCounters total = retired_counters_;
    total += refiner_->counters();
    return total;
}

RefinedMesh Pipeline::mesh() const {
    return refiner_->mesh();
}

MeshDelta Pipeline::snapshot() const {
    return refiner_->snapshot();
}

}  // namespace isomesh
