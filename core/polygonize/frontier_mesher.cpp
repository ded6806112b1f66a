// The mesh of an octree's frontier, steps 2 to 6 of phase 1 (see polygonizer.cpp for the whole):
// 2. corner values of the leaves, evaluated once each, in batches;
// 3. crossings: each crossed leaf edge is narrowed by bisection to the step of the finest leaf
//    where f changes sign (crossing_vertices.h), which names its vertex, so leaves of different
//    sizes sharing a lattice line share the vertex;
// 4. the frontier is graded along the surface (a leaf is split while a neighbour across a face
//    the surface crosses is two levels finer), then Marching Cubes 33 runs in every leaf
//    (leaf_mesher.h), with crack patching where a neighbour is finer; leaves whose faces do not
//    match their finer neighbours are split and everything is meshed again, until all match. The
//    thesis refines every surface cell to one common depth instead, which is simpler but lets one
//    small feature (a thin neck, a crease) refine the whole surface: millions of triangles where
//    tens of thousands suffice. These splits belong to this mesh only: the octree keeps its own
//    frontier, so that its final state does not depend on when meshes were made;
// 5. one root per crossing used, found on its finest step by safeguarded Newton iteration with
//    the gradient (edge_roots.h); crossings that are poles or jumps are no roots, and the
//    triangles touching them are dropped;
// 6. thin triangle cleanup (thin_triangle_cleanup.h), then adjacency and base edges
//    (mesh/topology.h).
// Every parallel step stores its results by task index and merges them in index order, and
// vertices are numbered by crossing, so the mesh is the same for every thread count.
#include "polygonize/frontier_mesher.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <iterator>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>

#include "mesh/topology.h"
#include "polygonize/ancestor_path.h"
#include "polygonize/crossing_roots.h"
#include "polygonize/crossing_vertices.h"
#include "polygonize/edge_roots.h"
#include "polygonize/leaf_index.h"
#include "polygonize/leaf_mesher.h"
#include "polygonize/mc33.h"
#include "polygonize/thin_triangle_cleanup.h"

namespace isomesh {
namespace {
constexpr std::size_t kPointsPerTask = 1024;
constexpr std::size_t kEdgesPerTask = 256;
/// Crossings located in lockstep (locate_crossings) between two looks at the cancellation flag.
constexpr std::size_t kEdgesPerBatch = 64;
constexpr std::size_t kCellsPerTask = 256;
/// Cleanup thresholds; the edge length is relative to the lattice step of the deepest leaf.
constexpr double kMinEdgeFraction = 0.1;
constexpr double kMinQuality = 0.1;

std::vector<CellId> cells_of(const std::vector<FrontierCell>& frontier) {
    std::vector<CellId> cells;
    cells.reserve(frontier.size());
    for (const FrontierCell& f : frontier) cells.push_back(f.cell);
    return cells;
}

int deepest(const std::vector<FrontierCell>& frontier) {
    int depth = 0;
    for (const FrontierCell& f : frontier) depth = std::max(depth, f.cell.depth);
    return depth;
}

/// Evaluates f, in batches, at the corners of `leaves` not in `values`.
void evaluate_corners(EvaluatorPool& workers, const Lattice& lattice,
                      const std::vector<CellId>& leaves, ValueMap& values,
                      const WorkBudget& budget) {
    std::vector<std::uint64_t> missing;
    for (const CellId& cell : leaves) {
        for (int c = 0; c < 8; ++c) {
            const std::uint64_t key = Lattice::key(lattice.corner(cell, c));
            if (!values.contains(key)) missing.push_back(key);
        }
    }
    std::sort(missing.begin(), missing.end());
    missing.erase(std::unique(missing.begin(), missing.end()), missing.end());
    std::vector<double> results(missing.size());
    workers.for_each(task_count(missing.size(), kPointsPerTask),
                     [&](std::size_t task, CountingEvaluator& evaluator) {
                         if (budget.cancelled()) return;
                         const std::size_t begin = task * kPointsPerTask;
                         const std::size_t n = std::min(kPointsPerTask, missing.size() - begin);
                         std::vector<double> x(n), y(n), z(n);
                         for (std::size_t i = 0; i < n; ++i) {
                             const glm::dvec3 p = lattice.point(Lattice::unkey(missing[begin + i]));
                             x[i] = p.x;
                             y[i] = p.y;
                             z[i] = p.z;
                         }
                         evaluator.values({x, y, z}, std::span(results).subspan(begin, n));
                     });
    if (budget.cancelled()) return;
    for (std::size_t i = 0; i < missing.size(); ++i) values.emplace(missing[i], results[i]);
}

/// Locates the crossing of every edge of `leaves` whose ends are on different sides and that is
/// not in `crossings` yet (crossing_vertices.h), on steps of `finest_depth`, adding the values it
/// evaluates to `values`.
void locate_leaf_crossings(EvaluatorPool& workers, const Lattice& lattice,
                           const std::vector<CellId>& leaves, int finest_depth, ValueMap& values,
                           IdMap<CrossingKey>& crossings, const WorkBudget& budget) {
    std::vector<std::pair<std::uint64_t, CellEdge>> edges;  // by cell_edge_key
    for (const CellId& cell : leaves) {
        for (int e = 0; e < 12; ++e) {
            const auto [c0, c1] = kEdgeCorners[e];
            const glm::u32vec3 p0 = lattice.corner(cell, c0);
            if (is_inside(values.at(Lattice::key(p0))) ==
                is_inside(values.at(Lattice::key(lattice.corner(cell, c1))))) {
                continue;
            }
            const std::uint64_t key = cell_edge_key(p0, e / 4, cell.depth);
            if (!crossings.contains(key)) edges.push_back({key, {p0, e / 4, cell.depth}});
        }
    }
    const auto by_key = [](const auto& a, const auto& b) { return a.first < b.first; };
    std::sort(edges.begin(), edges.end(), by_key);
    edges.erase(std::unique(edges.begin(), edges.end(),
                            [](const auto& a, const auto& b) { return a.first == b.first; }),
                edges.end());
    std::vector<CellEdge> cell_edges;
    cell_edges.reserve(edges.size());
    for (const auto& [key, edge] : edges) cell_edges.push_back(edge);
    std::vector<CrossingKey> located(edges.size());
    std::vector<ValueMap> evaluated(task_count(edges.size(), kEdgesPerTask));
    workers.for_each(evaluated.size(), [&](std::size_t task, CountingEvaluator& evaluator) {
        if (budget.cancelled()) return;
        CornerCache cache(evaluator, lattice, &values);
        const std::size_t end = std::min(edges.size(), (task + 1) * kEdgesPerTask);
        // Cancellation is checked between batches (each bisects up to 16 levels: on a long tape
        // a whole task's would take milliseconds).
        for (std::size_t i = task * kEdgesPerTask; i < end && !budget.cancelled();
             i += kEdgesPerBatch) {
            const std::size_t n = std::min(end - i, kEdgesPerBatch);
            locate_crossings(cache, lattice, std::span(cell_edges).subspan(i, n), finest_depth,
                             std::span(located).subspan(i, n));
        }
        evaluated[task] = std::move(cache.values());
    });
    if (budget.cancelled()) return;
    for (ValueMap& part : evaluated) values.merge(part);
    for (std::size_t i = 0; i < edges.size(); ++i) crossings.emplace(edges[i].first, located[i]);
}

/// The subtrees replacing cells `which` (in octree order): a pending cell's 8 children, pending
/// too; a settled cell's leaves of its classified subtree (split_settled), or, in a mesh of an
/// unfinished octree (`preview`), its 8 children as pending cells too (classifying a subtree there
/// could cost more than the whole octree so far). Once the budget is exhausted, no cell but the
/// first starts: the result holds the subtrees of as many of `which`, from the first on, as were
/// split (the others are left as they were, for the next call).
std::vector<std::vector<FrontierCell>> split_cells(EvaluatorPool& workers, const Lattice& lattice,
                                                   const OctreeSettings& settings,
                                                   std::span<const FrontierCell> which,
                                                   bool preview, ValueMap& values,
                                                   const WorkBudget& budget) {
    std::vector<std::vector<FrontierCell>> subtrees(which.size());
    std::vector<ValueMap> evaluated(which.size());
    std::vector<std::uint8_t> done(which.size(), 0);
    workers.for_each(which.size(), [&](std::size_t i, CountingEvaluator& evaluator) {
        if (budget.cancelled() || (i > 0 && budget.exhausted())) return;
        const CellId& cell = which[i].cell;
        if (which[i].state == CellState::Pending || preview) {
            for (int octant = 0; octant < 8; ++octant)
                subtrees[i].push_back({cell.child(octant), CellState::Pending});
        } else {
            subtrees[i] =
                split_settled(evaluator, lattice, settings, cell, values, evaluated[i], budget);
        }
        done[i] = 1;
    });
    // The cells split in a row from the first (tasks run in any order): the same frontier
    // whatever the threads' timing.
    const auto count =
        static_cast<std::size_t>(std::find(done.begin(), done.end(), 0) - done.begin());
    subtrees.resize(count);
    for (std::size_t i = 0; i < count; ++i) values.merge(evaluated[i]);
    return subtrees;
}

}  // namespace

/// The mesh of a frontier (steps 2 to 6 of the file comment), made over one or several calls of
/// advance(): the work goes in chunks of a few thousand leaves or crossings, the budget checked
/// between them, and what a call leaves undone the next one takes up, so that the mesh does not
/// depend on where budgets cut it.
class FrontierMesher::Impl {
  public:
    Impl(EvaluatorPool& workers, const Lattice& lattice, const OctreeSettings& settings,
         ValueMap& values, std::vector<FrontierCell> frontier, bool adjacency)
        : adjacency_(adjacency),
          workers_(workers),
          lattice_(lattice),
          settings_(settings),
          values_(values),
          frontier_(std::move(frontier)) {
        preview_ = std::any_of(frontier_.begin(), frontier_.end(),
                               [](const FrontierCell& f) { return f.state == CellState::Pending; });
        leaves_ = cells_of(frontier_);
        finest_ = deepest(frontier_);
        fresh_ = leaves_;
        unlocated_ = leaves_;
        index_.emplace(leaves_);
        states_.resize(leaves_.size());
    }

    /// Goes on until the mesh is made (true) or the budget is exhausted or cancelled (false).
    bool advance(const WorkBudget& budget) {
        budget_ = &budget;
        while (stage_ != Stage::done) {
            if (budget.cancelled() || !run_chunk()) return false;
            if (stage_ != Stage::done && budget.exhausted()) return false;
        }
        return true;
    }

    /// The mesh. Precondition: advance() returned true.
    PolygonizeResult take() { return std::move(result_); }

  private:
    /// Grades the frontier, then meshes every leaf; splits the leaves whose faces do not match
    /// their finer neighbours, and again, until all match (leaves of equal size always do, so
    /// this ends). Incremental: after a split, only the new leaves and the leaves across the
    /// split cells' faces are graded and meshed again (a leaf's grading and mesh depend only on
    /// itself and its face neighbours), so the result is that of meshing everything each time.
    /// Then the roots of the crossings used, the mesh, its cleanup, its adjacency.
    enum class Stage { corners, grade, split, locate, mesh, roots, assemble, clean, finish, done };

    /// A leaf's meshing state, kept beside leaves_.
    struct LeafState {
        std::unique_ptr<LeafMeshes> mesh;  // none while it has no triangles (most leaves)
        bool grade = true;                 // needs_grading must look at it (again)
        bool stale = true;                 // its mesh must be made (again)
    };

    /// Leaves, crossings or cells handled between two looks at the budget.
    static constexpr std::size_t kChunk = 4096;
    /// Cells split between two looks: fewer, since a settled cell's split classifies its whole
    /// subtree down to the finest depth (0.15 ms a cell on colonnade.vm: 4,096 took 612 ms, and
    /// 256 up to 250 ms on bear.vm); a chunk also stops starting cells once the budget is
    /// exhausted (split_cells).
    static constexpr std::size_t kSplitChunk = 256;

    /// One chunk of the current stage; false when cancelled midway (the chunk is done again).
    bool run_chunk() {
        switch (stage_) {
            case Stage::corners:
                return evaluate_fresh_corners();
            case Stage::grade:
                return select_chunk(&LeafState::grade, [this](std::size_t i) {
                    return needs_grading(input(), leaves_[i]);
                });
            case Stage::split:
                split_chunk();
                return !budget_->cancelled();
            case Stage::locate:
                return locate_chunk();
            case Stage::mesh:
                return select_chunk(
                    &LeafState::stale,
                    [this](std::size_t i, CountingEvaluator& evaluator, AncestorPath& path) {
                        return !mesh_stale_leaf(i, evaluator, path);
                    });
            case Stage::roots:
                return roots_chunk();
            case Stage::assemble:
                result_.mesh = assemble_mesh(roots_, parts_);
                stage_ = Stage::clean;
                return true;
            case Stage::clean:
                clean();
                return true;
            case Stage::finish:
                finish();
                return !budget_->cancelled();
            case Stage::done:
                return true;
        }
        return true;
    }

    LeafMeshingInput input() const { return {lattice_, values_, crossings_, *index_}; }

    bool evaluate_fresh_corners() {
        const std::size_t n = std::min(kChunk, fresh_.size());
        const std::vector<CellId> chunk(fresh_.end() - static_cast<std::ptrdiff_t>(n),
                                        fresh_.end());
        evaluate_corners(workers_, lattice_, chunk, values_, *budget_);
        if (budget_->cancelled()) return false;  // corners are missing: nothing below may run
        fresh_.resize(fresh_.size() - n);
        if (fresh_.empty()) begin_selection(Stage::grade, &LeafState::grade);
        return true;
    }

    /// Starts a stage that looks at every leaf with `flag` set.
    void begin_selection(Stage stage, bool LeafState::*flag) {
        stage_ = stage;
        candidates_ = flagged(flag);
        cursor_ = 0;
        selected_.clear();
    }

    /// Runs `predicate` on the next chunk of candidates_, gathering those it holds for; once all
    /// are seen, moves on: to splitting them if any, else to the next stage.
    template <typename Predicate>
    bool select_chunk(bool LeafState::*flag, const Predicate& predicate) {
        const std::size_t end = std::min(candidates_.size(), cursor_ + kChunk);
        const std::vector<std::size_t> chunk(candidates_.begin() + cursor_,
                                             candidates_.begin() + end);
        const std::vector<std::size_t> chosen = select(chunk, predicate);
        if (budget_->cancelled()) return false;
        for (std::size_t i : chunk) states_[i].*flag = false;
        selected_.insert(selected_.end(), chosen.begin(), chosen.end());
        cursor_ = end;
        if (cursor_ < candidates_.size()) return true;
        if (!selected_.empty()) {
            begin_split();
        } else if (stage_ == Stage::grade) {
            stage_ = Stage::locate;
        } else {
            begin_roots();
        }
        return true;
    }

    void begin_split() {
        to_split_.clear();
        for (std::size_t i : selected_) to_split_.push_back(leaves_[i]);
        split_cursor_ = 0;
        stage_ = Stage::split;
    }

    void split_chunk() {
        const std::size_t end = std::min(to_split_.size(), split_cursor_ + kSplitChunk);
        split_cursor_ += split({to_split_.begin() + split_cursor_, to_split_.begin() + end});
        if (split_cursor_ == to_split_.size()) stage_ = Stage::corners;
    }

    bool locate_chunk() {
        const std::size_t n = std::min(kChunk, unlocated_.size());
        const std::vector<CellId> chunk(unlocated_.end() - static_cast<std::ptrdiff_t>(n),
                                        unlocated_.end());
        locate_leaf_crossings(workers_, lattice_, chunk, finest_, values_, crossings_, *budget_);
        if (budget_->cancelled()) return false;
        unlocated_.resize(unlocated_.size() - n);
        if (unlocated_.empty()) begin_selection(Stage::mesh, &LeafState::stale);
        return true;
    }

    void begin_roots() {
        for (LeafState& state : states_) {
            if (state.mesh) parts_.push_back(std::move(*state.mesh));
        }
        states_.clear();
        roots_ = crossings_used(parts_, lattice_, finest_);
        cursor_ = 0;
        stage_ = Stage::roots;
    }

    bool roots_chunk() {
        const std::size_t end = std::min(roots_.keys.size(), cursor_ + kChunk);
        find_roots(workers_, lattice_, values_, roots_, cursor_, end, *budget_);
        if (budget_->cancelled()) return false;
        cursor_ = end;
        if (cursor_ == roots_.keys.size()) stage_ = Stage::assemble;
        return true;
    }

    void clean() {
        PolygonizeStats& stats = result_.stats;
        stats.cells = leaves_.size();
        stats.depth = finest_;
        for (const FrontierCell& f : frontier_) {
            stats.unresolved_cells += f.state != CellState::Leaf;
            stats.pending_cells += f.state == CellState::Pending;
        }
        const glm::dvec3 step = lattice_.box().size() / std::ldexp(1.0, stats.depth);
        const ThinTriangleSettings cleanup{kMinEdgeFraction * std::min({step.x, step.y, step.z}),
                                           kMinQuality};
        const ThinTriangleReport report =
            remove_thin_triangles(result_.mesh, box_faces(result_.mesh, lattice_.box()), cleanup);
        stats.collapses = report.collapses;
        stats.flips = report.flips;
        stage_ = Stage::finish;
    }

    void finish() {
        if (adjacency_) build_adjacency(result_.mesh);
        stage_ = Stage::done;
    }

    /// Meshes stale leaf i; false when it did not match.
    bool mesh_stale_leaf(std::size_t i, CountingEvaluator& evaluator, AncestorPath& path) {
        LeafState& state = states_[i];
        LeafMeshes mesh;
        mesh_leaf(evaluator, input(), leaves_[i], mesh, &path);
        const bool matched = mesh.unmatched.empty();
        state.mesh = mesh.triangles.empty() && mesh.extra_positions.empty()
                         ? nullptr
                         : std::make_unique<LeafMeshes>(std::move(mesh));
        return matched;
    }

    /// The indices of the leaves with `flag` set, in order.
    std::vector<std::size_t> flagged(bool LeafState::*flag) const {
        std::vector<std::size_t> out;
        for (std::size_t i = 0; i < states_.size(); ++i) {
            if (states_[i].*flag) out.push_back(i);
        }
        return out;
    }

    /// Those of `candidates` (leaf indices, in order) for which `predicate` holds, evaluated in
    /// parallel (the predicate may take the task's evaluator and a walk of it along the task's
    /// leaves, which are in octree order), in order.
    template <typename Predicate>
    std::vector<std::size_t> select(const std::vector<std::size_t>& candidates,
                                    const Predicate& predicate) {
        std::vector<std::uint8_t> chosen(candidates.size());
        workers_.for_each(
            task_count(candidates.size(), kCellsPerTask),
            [&](std::size_t task, CountingEvaluator& evaluator) {
                const std::size_t end = std::min(candidates.size(), (task + 1) * kCellsPerTask);
                AncestorPath path(evaluator, lattice_);
                for (std::size_t k = task * kCellsPerTask; k < end && !budget_->cancelled(); ++k) {
                    if constexpr (std::is_invocable_v<Predicate, std::size_t>) {
                        chosen[k] = predicate(candidates[k]);
                    } else {
                        chosen[k] = predicate(candidates[k], evaluator, path);
                    }
                }
            });
        std::vector<std::size_t> result;
        for (std::size_t k = 0; k < candidates.size(); ++k) {
            if (chosen[k]) result.push_back(candidates[k]);
        }
        return result;
    }

    /// Splits the leaves `cells` (in order), or as many of them from the first on as the budget
    /// allows (returned), keeping the index, the leaves' states and the crossings up to date.
    std::size_t split(const std::vector<CellId>& cells) {
        std::vector<FrontierCell> which;
        std::vector<std::size_t> at;  // their indices in leaves_
        for (const CellId& cell : cells) {
            at.push_back(position(cell));
            which.push_back(frontier_[at.back()]);
        }
        const std::vector<std::vector<FrontierCell>> subtrees =
            split_cells(workers_, lattice_, settings_, which, preview_, values_, *budget_);
        const std::size_t count = subtrees.size();
        const std::size_t before = fresh_.size();
        for (const std::vector<FrontierCell>& subtree : subtrees) {
            for (const FrontierCell& f : subtree) fresh_.push_back(f.cell);
        }
        replace_leaves(std::span(at).first(count), subtrees);
        for (const CellId& cell : std::span(cells).first(count)) {
            for (const CellId& n : index_->face_neighbours(cell)) {
                LeafState& state = states_[position(n)];
                state.grade = state.stale = true;
            }
        }
        int finest = finest_;
        for (std::size_t i = before; i < fresh_.size(); ++i)
            finest = std::max(finest, fresh_[i].depth);
        if (finest != finest_) {
            // Crossings are named by steps of the finest leaf: all are located again.
            finest_ = finest;
            crossings_.clear();
            unlocated_ = leaves_;
            for (LeafState& state : states_) state.stale = true;
        } else {
            unlocated_.insert(unlocated_.end(), fresh_.begin() + before, fresh_.end());
        }
        return count;
    }

    /// Replaces leaves at[i] (ascending) by subtrees[i] in the frontier, the leaves and their
    /// states (the new leaves start fresh, and the index learns of them), in one pass that keeps
    /// the octree order; the old arrays become the next call's scratch space.
    void replace_leaves(std::span<const std::size_t> at,
                        const std::vector<std::vector<FrontierCell>>& subtrees) {
        std::size_t size = frontier_.size() - at.size();
        for (const std::vector<FrontierCell>& subtree : subtrees) size += subtree.size();
        next_frontier_.clear();
        next_leaves_.clear();
        next_states_.clear();
        next_frontier_.reserve(size);
        next_leaves_.reserve(size);
        next_states_.reserve(size);
        std::size_t kept = 0;  // the next old leaf to keep
        const auto keep_until = [&](std::size_t end) {
            next_frontier_.insert(next_frontier_.end(), frontier_.begin() + kept,
                                  frontier_.begin() + end);
            next_leaves_.insert(next_leaves_.end(), leaves_.begin() + kept, leaves_.begin() + end);
            std::move(states_.begin() + kept, states_.begin() + end,
                      std::back_inserter(next_states_));
        };
        std::vector<CellId> new_leaves;
        for (std::size_t i = 0; i < at.size(); ++i) {
            keep_until(at[i]);
            kept = at[i] + 1;
            new_leaves.clear();
            for (const FrontierCell& f : subtrees[i]) {
                next_frontier_.push_back(f);
                next_leaves_.push_back(f.cell);
                next_states_.emplace_back();
                new_leaves.push_back(f.cell);
            }
            index_->replace(leaves_[at[i]], new_leaves);
        }
        keep_until(leaves_.size());
        std::swap(frontier_, next_frontier_);
        std::swap(leaves_, next_leaves_);
        std::swap(states_, next_states_);
    }

    /// The index in leaves_ of `leaf` (leaves_ is in octree order: a binary search).
    std::size_t position(const CellId& leaf) const {
        const std::uint64_t order = lattice_.octree_order(leaf);
        const auto it = std::lower_bound(
            leaves_.begin(), leaves_.end(), order,
            [&](const CellId& c, std::uint64_t o) { return lattice_.octree_order(c) < o; });
        assert(it != leaves_.end() && *it == leaf);
        return static_cast<std::size_t>(it - leaves_.begin());
    }

    bool adjacency_;  // build the mesh's adjacency at the end (PolygonizeSettings::adjacency)
    EvaluatorPool& workers_;
    const Lattice& lattice_;
    const OctreeSettings& settings_;
    ValueMap& values_;
    const WorkBudget* budget_ = nullptr;  // of the advance() under way
    std::vector<FrontierCell> frontier_;
    bool preview_ = false;  // some cell is pending: the octree is unfinished
    std::vector<CellId> leaves_;
    std::optional<LeafIndex> index_;  // of leaves_
    std::vector<LeafState> states_;   // of leaves_
    int finest_ = 0;
    IdMap<CrossingKey> crossings_;
    std::vector<CellId> fresh_;      // leaves whose corners are not evaluated yet
    std::vector<CellId> unlocated_;  // leaves whose crossings are not located yet
    Stage stage_ = Stage::corners;
    std::vector<std::size_t> candidates_;  // leaves the current selection looks at
    std::size_t cursor_ = 0;               // in candidates_, or in roots_.order
    std::vector<std::size_t> selected_;    // those of candidates_ seen so far that it chose
    std::vector<CellId> to_split_;
    std::size_t split_cursor_ = 0;
    // The arrays replace_leaves() fills, kept for their capacity.
    std::vector<FrontierCell> next_frontier_;
    std::vector<CellId> next_leaves_;
    std::vector<LeafState> next_states_;
    std::vector<LeafMeshes> parts_;
    CrossingRoots roots_;
    PolygonizeResult result_;
};

FrontierMesher::FrontierMesher(EvaluatorPool& workers, const Lattice& lattice,
                               const OctreeSettings& settings, ValueMap& values,
                               std::vector<FrontierCell> frontier, bool adjacency)
    : impl_(std::make_unique<Impl>(workers, lattice, settings, values, std::move(frontier),
                                   adjacency)) {}

FrontierMesher::~FrontierMesher() = default;

bool FrontierMesher::advance(const WorkBudget& budget) {
    return impl_->advance(budget);
}

PolygonizeResult FrontierMesher::take() {
    return impl_->take();
}

}  // namespace isomesh
