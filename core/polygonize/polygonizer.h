// Phase 1 of the algorithm (thesis 3.3.2): a crude but topologically correct mesh of the surface
// f = 0 inside a box, from an octree and Marching Cubes 33, with every vertex on the surface.
// This is the mesh that progressive refinement (refine/) starts from.
//
// Two ways in: polygonize() runs phase 1 to the end and returns its mesh; a Polygonizer does the
// same work a slice at a time (classify some cells, then mesh whatever the octree holds so far),
// so that a first mesh can leave within milliseconds whatever the function, and sharper ones
// follow (progressive/pipeline.h).
#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "eval/evaluator.h"
#include "mesh/mesh.h"
#include "polygonize/evaluator_pool.h"
#include "polygonize/octree.h"
#include "work/work_budget.h"

namespace isomesh {

/// Everything one render needs, including its cancellation flag.
struct PolygonizeSettings {
    /// The meshing box: finite, lo < hi on every axis. GeoGebra's usual view by default.
    Box box{{-5.0, -5.0, -5.0}, {5.0, 5.0, 5.0}};
    /// Every octree cell down to min_depth is examined (so no coarse cell hides a surface); below
    /// it cells are split only where the surface may be and its topology is not yet certain, down
    /// to max_depth. 0 <= min_depth <= max_depth <= 16 (kMaxOctreeDepth).
    int min_depth = 4;
    int max_depth = 9;
    /// Levels below max_depth where cells that may hide a small feature (a critical point of f:
    /// a tiny closed component, a bubble) keep being split (octree.h), up to depth 16. >= 0.
    int feature_levels = 3;
    /// The most octree cells kept (a memory bound; octree.h).
    std::size_t max_cells = 2'000'000;
    /// Threads of its parallel loops (the caller's included); 0 = one per hardware thread. The
    /// output does not depend on it.
    int threads = 0;
    /// Where the loops find their threads besides the caller's (work/helpers.h): null starts
    /// threads - 1 for each loop; an executor (a server's worker pool) lends up to threads - 1
    /// of its idle ones. Must outlive the polygonization.
    Helpers* helpers = nullptr;
    /// Fill in the mesh's neighbours and base edges (mesh.h). false leaves them empty for a
    /// caller that changes the mesh first and builds them after (mesh/build_adjacency): the
    /// pipeline simplifies a large phase-1 mesh to the budget, and on the blobby cube's 712,536
    /// triangles they took 0.33 s in one step.
    bool adjacency = true;
    /// Checked regularly: when it becomes true, polygonize returns early with an empty mesh and
    /// stats.cancelled set. May be null.
    const std::atomic<bool>* cancel = nullptr;
};

struct PolygonizeStats {
    std::size_t evaluations = 0;           ///< point evaluations of f (value, or with gradient)
    std::size_t interval_evaluations = 0;  ///< interval evaluations (with or without gradient)
    std::size_t cells = 0;                 ///< octree leaves meshed
    /// Leaves meshed without the topology guarantee: accepted at the deepest level unproven, or
    /// not yet classified (a mesh of an unfinished octree).
    std::size_t unresolved_cells = 0;
    std::size_t pending_cells = 0;  ///< of those, cells not yet classified
    std::size_t region_cells = 0;   ///< cells on which f is zero everywhere (no surface: octree.h)
    std::size_t triangles = 0;
    std::size_t vertices = 0;
    std::size_t collapses = 0;  ///< edge collapses of the thin-triangle cleanup
    std::size_t flips = 0;      ///< edge flips of the thin-triangle cleanup
    double time_ms = 0.0;
    int depth = 0;  ///< the depth of the deepest leaf
    bool cancelled = false;

    /// Every cell was classified and met the leaf conditions: the mesh has the surface's topology.
    bool certified() const { return unresolved_cells == 0 && region_cells == 0; }
};

struct PolygonizeResult {
    Mesh mesh;
    PolygonizeStats stats;
};

/// Throws std::invalid_argument (saying what is wrong) when settings are out of range.
void validate(const PolygonizeSettings& settings);

/// Phase 1 a slice at a time. Not thread-safe; its work runs on its own evaluator pool.
class FrontierMesher;  // frontier_mesher.h

class Polygonizer {
  public:
    /// Throws std::invalid_argument for invalid settings or a null field.
    Polygonizer(std::shared_ptr<const Field> field, const PolygonizeSettings& settings);
    ~Polygonizer();

    /// Classifies octree cells, the largest first, until all are classified, a region where f
    /// is zero is found, the budget is exhausted, or the octree's frontier holds about
    /// `max_frontier` cells (a first mesh meant to be quick stops there).
    void advance(const WorkBudget& budget, std::size_t max_frontier = ~std::size_t{0});
    /// All cells are classified (or a region was found): mesh() is phase 1's final mesh.
    bool complete() const { return octree_.complete() || octree_.found_region(); }
    /// Stops the classification for good: pending cells become unresolved.
    void settle() { octree_.settle_pending(); }

    /// The mesh of the octree as it stands (see polygonize()); pending cells are meshed from their
    /// corners like leaves, without the guarantee. Runs to its end unless the budget is cancelled
    /// (then the mesh is empty and stats.cancelled set); its time limit is not checked.
    PolygonizeResult mesh(const WorkBudget& budget);
    /// mesh() over as many calls as the budgets need (the final mesh of a large octree takes
    /// seconds): each call goes on with the mesh the last one left unfinished, or starts one,
    /// and returns it once made, the same as mesh() makes. A cancelled call drops the unfinished
    /// mesh. Precondition: the octree does not change between the calls (complete(), or no
    /// advance() or settle() in between).
    /// A mesh started with `max_cells` is of the frontier coarsened to at most that many cells
    /// (octree.h: coarsened), a preview whose cost that bounds; the frontier as it stands
    /// otherwise.
    std::optional<PolygonizeResult> mesh_slice(const WorkBudget& budget,
                                               std::size_t max_cells = ~std::size_t{0});

    const OctreeCounts& counts() const { return octree_.counts(); }
    /// Evaluations made so far, by every worker.
    std::size_t evaluations() const { return pool_.point_evaluations(); }
    std::size_t interval_evaluations() const { return pool_.interval_evaluations(); }
    const PolygonizeSettings& settings() const { return settings_; }

  private:
    std::shared_ptr<const Field> field_;
    PolygonizeSettings settings_;
    EvaluatorPool pool_;
    Lattice lattice_;
    Octree octree_;
    ValueMap values_;
    /// A mesh under way in slices (mesh_slice).
    struct Slicing {
        std::unique_ptr<FrontierMesher> mesher;  // null where a region was found
        std::size_t points_before = 0;
        std::size_t intervals_before = 0;
        std::chrono::steady_clock::duration time{};
    };
    std::unique_ptr<Slicing> slicing_;
};

/// Meshes the surface f = 0 of `field` inside settings.box: Polygonizer run to the end.
///
/// The output mesh (see mesh.h for the invariants) has its vertices on the surface (found by root
/// finding along lattice edges with the gradient, |f| / |grad f| at rounding level), unit gradient
/// normals, triangles counter-clockwise seen from f > 0, neighbours and base edges filled in, no
/// zero-area triangle, and every edge shared by two triangles except where the surface leaves the
/// box (or ends at a pole or at the border of f's domain). Sign changes of f that are not roots
/// (poles such as 1/x = 0, jumps) produce no surface. Cells are as small as the surface's
/// topology needs where it needs it (octree.h), and cells of different sizes meet without cracks
/// (leaf_mesher.h). Where f is zero on a whole cell the equation holds on a region and the result
/// is empty, with stats.region_cells > 0. Identical for every thread count.
///
/// Throws std::invalid_argument for an invalid box or depths; exceptions from the field's
/// evaluators are passed on.
PolygonizeResult polygonize(const Field& field, const PolygonizeSettings& settings);

/// For each vertex of `mesh`, bit 2 * axis + side for each face of `box` it lies on: what the
/// collapses of thin-triangle cleanup and simplification keep on the box (mesh/edge_collapse.h).
std::vector<std::uint8_t> box_faces(const Mesh& mesh, const Box& box);

}  // namespace isomesh
