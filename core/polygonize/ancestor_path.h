// Per-cell tape simplification along an octree walk (libfive's technique; Keeter, SIGGRAPH
// 2020): the evaluator is specialised (Evaluator::push) to a cell through each of its ancestors
// in turn, so that each push simplifies the tape its parent already simplified, and a walk in
// octree order keeps the ancestors it shares with the previous cell. One push of a deep cell from
// the whole tape costs a full interval evaluation; from its parent's tape, a short one.
#pragma once

#include <cstddef>
#include <vector>

#include "eval/evaluator.h"
#include "polygonize/lattice.h"

namespace isomesh {

/// The chain of cells the evaluator is specialised to, root first. Pops them all when destroyed.
class AncestorPath {
  public:
    AncestorPath(Evaluator& evaluator, const Lattice& lattice)
        : evaluator_(evaluator), lattice_(lattice) {}
    ~AncestorPath() { walk_to_depth(0); }
    AncestorPath(const AncestorPath&) = delete;
    AncestorPath& operator=(const AncestorPath&) = delete;

    /// Specialises the evaluator to `cell` and its ancestors, reusing the specialisations of the
    /// ancestors it shares with the previous cell.
    void walk_to(const CellId& cell) {
        std::size_t common = 0;
        while (common < path_.size() && common <= static_cast<std::size_t>(cell.depth) &&
               path_[common] == cell.ancestor(static_cast<int>(common)))
            ++common;
        walk_to_depth(common);
        for (int level = static_cast<int>(path_.size()); level <= cell.depth; ++level) {
            const CellId ancestor = cell.ancestor(level);
            evaluator_.push(lattice_.cell_box(ancestor));
            path_.push_back(ancestor);
        }
    }

    /// Keeps the specialisations of the first `depth` cells of the chain only.
    void walk_to_depth(std::size_t depth) {
        while (path_.size() > depth) {
            evaluator_.pop();
            path_.pop_back();
        }
    }

  private:
    Evaluator& evaluator_;
    const Lattice& lattice_;
    std::vector<CellId> path_;  // path_[k]: the pushed ancestor at depth k
};

}  // namespace isomesh
