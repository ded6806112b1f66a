// Octree subdivision (see octree.h). Interval pruning of octrees for implicit
// surfaces follows Duff ("Interval arithmetic and recursive subdivision for implicit functions
// and constructive solid geometry", SIGGRAPH 1992) and Snyder (SIGGRAPH 1992); the per-cell tape
// simplification during the descent follows libfive (Keeter, "Massively parallel rendering of
// complex closed-form implicit surfaces", SIGGRAPH 2020).
#include "polygonize/octree.h"

#include <algorithm>
#include <cassert>

namespace isomesh {
namespace {

/// Root counting on a cell's edge bisects down to a quarter of the finest lattice step.
constexpr int kSubLatticeBisections = 2;
/// Subtrees are cut at this depth (or min_depth, if smaller): up to 8^2 = 64 tasks.
constexpr int kTaskDepth = 2;

bool is_cancelled(const OctreeSettings& settings) {
    return settings.cancel != nullptr && settings.cancel->load(std::memory_order_relaxed);
}

/// The cells at `depth` (all of them, in z-y-x order).
std::vector<CellId> cells_at_depth(int depth) {
    std::vector<CellId> cells;
    const std::uint32_t n = 1u << depth;
    for (std::uint32_t z = 0; z < n; ++z) {
        for (std::uint32_t y = 0; y < n; ++y) {
            for (std::uint32_t x = 0; x < n; ++x) cells.push_back({{x, y, z}, depth});
        }
    }
    return cells;
}

/// Whether f provably has no zero in `cell`, given its enclosure: by the natural interval, or
/// else by the mean value form around the cell's centre (a lattice point, kept in `corners`: it
/// is a corner of the cell's children if the cell is split).
bool provably_empty(Evaluator& evaluator, CornerCache& corners, const Lattice& lattice,
                    const CellId& cell, const IntervalGradient& enclosure) {
    if (enclosure.value.value.excludes_zero()) return true;
    if (enclosure.value.maybe_discontinuous || enclosure.value.maybe_undefined) return false;
    const Box box = lattice.cell_box(cell);
    const double center =
        cell.depth < lattice.max_depth()
            ? corners.value(lattice.origin(cell) + glm::u32vec3(lattice.span(cell.depth) / 2))
            : evaluator.value(box.center());
    return mean_value_excludes_zero(enclosure, center, box);
}

/// Depth-first walk of one subtree, down to the leaves of the classification.
class ClassificationWalk {
  public:
    ClassificationWalk(Evaluator& evaluator, const Lattice& lattice, const OctreeSettings& settings,
                       const std::unordered_map<std::uint64_t, double>* known = nullptr)
        : evaluator_(evaluator),
          lattice_(lattice),
          settings_(settings),
          corners_(evaluator, lattice, known) {}

    void visit(const CellId& cell) {
        if (is_cancelled(settings_)) return;
        const Box box = lattice_.cell_box(cell);
        if (cell.depth < settings_.min_depth) {
            if (evaluator_.interval(box).value.excludes_zero()) return;
            descend(cell, box);
            return;
        }
        const IntervalGradient enclosure = evaluator_.interval_gradient(box);
        if (provably_empty(evaluator_, corners_, lattice_, cell, enclosure)) return;
        const int bisections = lattice_.max_depth() - cell.depth + kSubLatticeBisections;
        switch (classify_cell(evaluator_, corners_, lattice_, cell, enclosure, bisections)) {
            case CellVerdict::Empty:
                return;
            case CellVerdict::Leaf:
                leaves.push_back(cell);
                return;
            case CellVerdict::Split:
                if (cell.depth == lattice_.max_depth()) {
                    leaves.push_back(cell);
                    ++unresolved;
                } else {
                    descend(cell, box);
                }
                return;
        }
    }

    CornerCache& corners() { return corners_; }

    void descend(const CellId& cell, const Box& box) {
        evaluator_.push(box);
        for (int octant = 0; octant < 8; ++octant) visit(cell.child(octant));
        evaluator_.pop();
    }

    std::vector<CellId> leaves;
    std::size_t unresolved = 0;

  private:
    Evaluator& evaluator_;
    const Lattice& lattice_;
    const OctreeSettings& settings_;
    CornerCache corners_;
};

}  // namespace

OctreeLeaves find_leaves(WorkerPool& workers, const Lattice& lattice,
                         const OctreeSettings& settings) {
    assert(settings.min_depth >= 0 && settings.min_depth <= settings.max_depth);
    assert(settings.max_depth == lattice.max_depth());
    OctreeLeaves result;
    const std::vector<CellId> roots = cells_at_depth(std::min(kTaskDepth, settings.min_depth));
    std::vector<std::vector<CellId>> subtree_leaves(roots.size());
    std::vector<std::unordered_map<std::uint64_t, double>> subtree_values(roots.size());
    std::vector<std::size_t> subtree_unresolved(roots.size());
    workers.for_each(roots.size(), [&](std::size_t i, CountingEvaluator& evaluator) {
        ClassificationWalk walk(evaluator, lattice, settings);
        walk.visit(roots[i]);
        subtree_leaves[i] = std::move(walk.leaves);
        subtree_values[i] = std::move(walk.corners().values());
        subtree_unresolved[i] = walk.unresolved;
    });
    for (std::size_t i = 0; i < roots.size(); ++i) {
        result.leaves.insert(result.leaves.end(), subtree_leaves[i].begin(),
                             subtree_leaves[i].end());
        result.known_values.merge(subtree_values[i]);
        result.unresolved += subtree_unresolved[i];
    }
    result.cancelled = is_cancelled(settings);
    return result;
}

OctreeLeaves split_leaf(Evaluator& evaluator, const Lattice& lattice,
                        const OctreeSettings& settings, const CellId& leaf,
                        const std::unordered_map<std::uint64_t, double>& known_values) {
    assert(leaf.depth < lattice.max_depth());
    ClassificationWalk walk(evaluator, lattice, settings, &known_values);
    walk.descend(leaf, lattice.cell_box(leaf));
    return {std::move(walk.leaves), std::move(walk.corners().values()), walk.unresolved, false};
}

}  // namespace isomesh
