// The octree of phase 1 (thesis 3.3.2), built anytime: the cells in which Marching Cubes 33 will
// mesh the surface, classified a few at a time, the largest first, so that whenever the work is
// interrupted (a time slice ends) the frontier covers the whole box at a uniform resolution, and
// a mesh can be made of it at once (polygonizer.h).
//
// Every cell is in one of these states:
// - pending: not yet classified (the mesh builder treats it as a leaf without guarantee);
// - leaf: Marching Cubes 33 on its corners has the surface's topology (cell_classification.h);
// - unresolved: it reached the deepest level without meeting the leaf conditions (meshed anyway,
//   without the topology guarantee: a singular point, a crease of a CSG model);
// - dropped: interval arithmetic proved f has no zero in it, or f is zero on all of it (a region
//   where the equation holds, which is not a surface: see regions()).
// Classification is a pure function of the cell, so the final frontier does not depend on how the
// work was cut into slices, nor on the number of threads.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "polygonize/cell_classification.h"
#include "polygonize/evaluator_pool.h"
#include "polygonize/lattice.h"
#include "work/work_budget.h"

namespace isomesh {

struct OctreeSettings {
    /// Every cell down to min_depth is examined (so that no coarse cell hides a surface that
    /// interval arithmetic cannot rule out); below it, cells are split only where the surface may
    /// be and its topology is not yet certain, down to max_depth.
    int min_depth = 4;
    int max_depth = 9;
    /// A cell that stays unresolved at max_depth although f is smooth in it and its gradient may
    /// vanish there (a critical point: a tiny closed component, a thin neck, a bubble) is split
    /// further, down to this depth. max_depth <= feature_depth <= kMaxOctreeDepth.
    int feature_depth = 12;
    /// The most cells the frontier may hold (a memory bound): past it, a cell that would be split
    /// is kept, unresolved.
    std::size_t max_cells = 2'000'000;
};

enum class CellState : std::uint8_t { Pending, Leaf, Unresolved };

struct FrontierCell {
    CellId cell;
    CellState state = CellState::Pending;
};

struct OctreeCounts {
    std::size_t pending = 0;
    std::size_t leaves = 0;
    std::size_t unresolved = 0;
    /// Cells on which f is zero everywhere (the equation holds on a region).
    std::size_t regions = 0;
    /// Cells classified so far.
    std::size_t classified = 0;
    /// Splits refused because the frontier was full (settings.max_cells), or because the search
    /// for small features below max_depth had used its share (octree.cpp).
    std::size_t capped = 0;
    /// Cells classified at max_depth.
    std::size_t at_max_depth = 0;
    /// The deepest level reached.
    int depth = 0;
};

/// What the classification decided for one cell (see octree.cpp for the rules).
enum class CellOutcome : std::uint8_t { Empty, Region, Leaf, Split, Unresolved };

/// The cells not yet classified, in level order (shallowest first, octree order within a level):
/// those of the level being classified, then the children made meanwhile (never more than these
/// two levels). Two arrays: a balanced tree paid an allocation and a rebalancing per cell.
class PendingCells {
  public:
    bool empty() const { return size_ == 0; }
    std::size_t size() const { return size_; }
    /// A cell one level below those being classified (or the root).
    void add(const CellId& cell);
    /// Appends up to `n` of the first pending cells, all of one level, to `out`: they are
    /// being classified (still counted as pending until classified()).
    void take_front(std::size_t n, std::vector<CellId>& out);
    /// One of the cells taken is classified.
    void classified() { --size_; }
    /// The cells taken last and not classified (in order) are pending again, first.
    void return_front(std::span<const CellId> cells);
    /// Every pending cell, in level order.
    std::vector<CellId> cells() const;
    void clear();

  private:
    std::vector<std::uint64_t> level_;  // level_order_key, sorted; pending from cursor_ on
    std::size_t cursor_ = 0;
    std::vector<std::uint64_t> next_;  // the level below, in the order made
    std::size_t size_ = 0;
};

class Octree {
  public:
    /// Starts with the root cell pending. Preconditions: lattice.max_depth() == kMaxOctreeDepth;
    /// 0 <= min_depth <= max_depth <= feature_depth <= kMaxOctreeDepth.
    Octree(const Lattice& lattice, const OctreeSettings& settings);

    /// Classifies pending cells, shallowest first and in octree order within a level, on the
    /// pool's workers (each walking its cells' ancestors with Evaluator::push/pop for tape
    /// simplification), until none is left, a region is found, the budget is exhausted (checked
    /// before every cell), or the frontier holds `max_frontier` cells (about: one classification
    /// may add up to 8). Values of f it evaluates are added to `values`.
    void advance(EvaluatorPool& pool, ValueMap& values, const WorkBudget& budget,
                 std::size_t max_frontier = ~std::size_t{0});

    /// No cell is pending.
    bool complete() const { return pending_.empty(); }
    /// f is zero on some whole cell: the equation holds on a region, which is no surface.
    bool found_region() const { return counts_.regions > 0; }
    /// Every pending cell becomes unresolved (the work is stopped for good).
    void settle_pending();

    /// The frontier (pending, leaf and unresolved cells), in octree order.
    std::vector<FrontierCell> frontier() const;
    const OctreeCounts& counts() const { return counts_; }
    const Lattice& lattice() const { return lattice_; }
    const OctreeSettings& settings() const { return settings_; }

  private:
    /// Classifies `cells` (one level, in octree order) in tasks on the pool's workers; an
    /// outcome is empty where the budget stopped its task first. Adds the values and edge root
    /// counts found to `values` and edge_counts_.
    std::vector<std::optional<CellOutcome>> classify_round(EvaluatorPool& pool, ValueMap& values,
                                                           std::span<const CellId> cells,
                                                           const WorkBudget& budget);
    /// Applies the outcomes of `round` (the cells taken, in order: those in ahead_ and the others,
    /// whose outcomes are `outcomes`, in order) up to the first cell without one; the rest are
    /// pending again, the outcomes known kept in ahead_.
    void apply_in_order(std::span<const CellId> round,
                        std::span<const std::optional<CellOutcome>> outcomes);
    void apply(const CellId& cell, CellOutcome outcome);
    /// Whether a cell to split may be: always above max_depth; below, while the search for small
    /// features has room left.
    bool feature_room(const CellId& cell);

    Lattice lattice_;
    OctreeSettings settings_;
    PendingCells pending_;
    std::vector<FrontierCell> settled_;
    OctreeCounts counts_;
    std::size_t feature_cells_ = 0;  // cells made by splits at or below max_depth
    /// Root counts of the edges of the cells classified at edge_counts_depth_ (the level being
    /// classified): neighbouring families share the edges of their common faces.
    EdgeRootCounts edge_counts_;
    int edge_counts_depth_ = -1;
    /// Outcomes of pending cells classified ahead of a cell a budget left unclassified (another
    /// worker's task ran on), by level_order_key, applied once the cells before them are.
    IdMap<CellOutcome> ahead_;
};

/// `frontier` (in octree order) with its deepest cells merged into their parents, level by level,
/// until it holds at most `max_cells` cells (or its cells are the root's children): a coarser
/// mesh of an unfinished octree, a preview that costs about as much as its cells. A parent takes
/// the place of its first child in the frontier and is pending (it was split, not classified as
/// a leaf): the mesh builder meshes it from its corners without the guarantee.
std::vector<FrontierCell> coarsened(std::vector<FrontierCell> frontier, std::size_t max_cells);

/// Replaces settled cell `cell` (a leaf or an unresolved cell the mesh builder must split to match
/// finer neighbours) by the leaves of its subtree: its children, classified like any cell (so the
/// guarantees hold for them), split further while they need it down to max_depth; a cell there or
/// below that would be split is unresolved (the search for small features is the octree's).
/// Values of f it evaluates go to `evaluated` (those in `known` are reused). Stops early (the
/// result is then incomplete) when the budget is cancelled. Precondition: cell.depth <
/// kMaxOctreeDepth.
std::vector<FrontierCell> split_settled(Evaluator& evaluator, const Lattice& lattice,
                                        const OctreeSettings& settings, const CellId& cell,
                                        const ValueMap& known, ValueMap& evaluated,
                                        const WorkBudget& budget);

}  // namespace isomesh
