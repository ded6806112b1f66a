// Simplification to a triangle budget: the thesis's "mid-phase simplification" (3.3.4), used
// where phase 1's mesh has more triangles than the session may show. Edges are collapsed
// cheapest first by the quadric error metric of Garland & Heckbert ("Surface simplification
// using quadric error metrics", SIGGRAPH 1997), as half-edge collapses that keep the topology
// (mesh/edge_collapse.h): the mesh keeps its components, genus and boundary loops, every vertex
// stays where it was (on the surface), the boundary stays on the faces of the meshing box, and no
// triangle flips.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "mesh/mesh.h"
#include "work/work_budget.h"

namespace isomesh {

/// Where a simplification stops. `limit`: the most triangles the result may have. `preferred`
/// (at most limit): fewer triangles to go on to where the topology allows; where it does not,
/// the result is the mesh as it was at the limit (collapsing on to the topology's floor would
/// only coarsen the parts the topology needs). Applies to a mesh over the limit only: a mesh
/// within it is kept as it is.
struct SimplifyTarget {
    std::size_t limit;
    std::size_t preferred;
    SimplifyTarget(std::size_t limit_triangles)  // NOLINT: a limit alone, nothing preferred
        : limit(limit_triangles), preferred(limit_triangles) {}
    SimplifyTarget(std::size_t limit_triangles, std::size_t preferred_triangles)
        : limit(limit_triangles), preferred(std::min(preferred_triangles, limit_triangles)) {}
};

struct SimplifyReport {
    std::size_t collapses = 0;
    std::size_t triangles = 0;  ///< after simplification
    /// triangles <= the limit. False when no allowed collapse was left first: the mesh is then
    /// as small as its topology (and the box) let these collapses make it.
    bool reached = false;
    /// triangles <= the preferred count (the result went on past the limit).
    bool reached_preferred = false;
    bool cancelled = false;
};

/// Collapses edges of `mesh` towards `target` (see SimplifyTarget), then compacts it (neighbours
/// and base edges are cleared). Deterministic. Stops early, leaving a valid mesh (the one at the
/// limit where it was reached), when the budget is cancelled or exhausted.
/// Preconditions: as CollapseMesh (manifold, consistently oriented, one normal per vertex,
/// box_faces.size() == vertex_count()).
SimplifyReport simplify_to_budget(Mesh& mesh, std::span<const std::uint8_t> box_faces,
                                  SimplifyTarget target, const WorkBudget& budget = {});

/// simplify_to_budget in slices: each advance() goes on where the last one stopped, so that a
/// large mesh (the blobby cube's 712,000 triangles) is simplified over many short steps. The
/// result does not depend on the slicing. Same preconditions as simplify_to_budget.
class Simplification {
  public:
    Simplification(Mesh mesh, std::vector<std::uint8_t> box_faces, SimplifyTarget target);
    ~Simplification();
    Simplification(const Simplification&) = delete;
    Simplification& operator=(const Simplification&) = delete;

    /// Collapses edges until the target is settled, no collapse is allowed or `budget` is
    /// exhausted; true once done (report().cancelled when the budget was cancelled).
    bool advance(const WorkBudget& budget);
    bool done() const { return done_; }
    const SimplifyReport& report() const { return report_; }
    /// The simplified mesh, compacted. Before done(), the mesh as it stands: the one at the
    /// limit where it was reached, else the collapses made so far.
    Mesh take();

  private:
    class Collapses;
    /// Settles the result once the collapses are over; returns true.
    bool finish();

    std::unique_ptr<Mesh> mesh_;  // where the collapses below point
    std::vector<std::uint8_t> box_faces_;
    std::unique_ptr<Collapses> collapses_;
    SimplifyTarget target_;
    std::optional<Mesh> at_limit_;  // kept while going on to the preferred count
    SimplifyReport report_;
    bool done_ = false;
};

}  // namespace isomesh
