// The anytime octree (see octree.h). Interval pruning of octrees for implicit surfaces follows
// Duff ("Interval arithmetic and recursive subdivision for implicit functions and constructive
// solid geometry", SIGGRAPH 1992) and Snyder (SIGGRAPH 1992); the per-cell tape simplification
// follows libfive (Keeter, "Massively parallel rendering of complex closed-form implicit
// surfaces", SIGGRAPH 2020), here along the ancestors of each cell of a breadth-first walk.
//
// The rules, for a cell whose enclosure of f (and, from min_depth on, of grad f) is known:
// - f's interval excludes 0, or the mean value form does: empty, dropped;
// - f is zero on the whole cell (its interval is exactly [0, 0]; or f is continuous with a
//   gradient enclosure of exactly zero and f(centre) = 0, so f is constant 0): a region where the
//   equation holds, which is no surface (`floor(x) = 0`, `0 = 0`, `x = x`): dropped and counted,
//   and the walk stops so that the caller can say so at once;
// - above min_depth: split;
// - otherwise cell_classification.h decides leaf, empty or split; a cell to split at max_depth is
//   unresolved, unless it may hide a small feature: f continuous, every component of its
//   gradient enclosure contains 0, all its corners on one side, and the gradients at the corners
//   all pointing away from the centre (outside: a minimum of f is likely inside) or towards it
//   (inside: a maximum), so that a tiny closed component, a bubble, could be there unseen by
//   Marching Cubes. Such a cell is split further, down to feature_depth, and in its subtree so
//   are the cells meeting the same conditions and the cells the bubble's surface crosses (their
//   corners change sign), until proven. (Where the corners of a cell at max_depth change sign,
//   Marching Cubes meshes what it sees; where an enclosure merely fails to exclude a vanishing
//   gradient, as on a CAD model's blends and creases or along a singular curve of f, deeper cells
//   would find nothing.)
#include "polygonize/octree.h"

#include <algorithm>
#include <array>
#include <cassert>

#include <glm/geometric.hpp>

#include "polygonize/ancestor_path.h"

namespace isomesh {
namespace {

/// Root counting on a cell's edge bisects down to a quarter of the finest regular level's step.
constexpr int kSubLatticeBisections = 2;
/// Cells per worker task (consecutive in octree order, so that they share most ancestors).
constexpr std::size_t kCellsPerTask = 256;
/// Cells per round of tasks handed to the pool.
constexpr std::size_t kCellsPerRound = 2048;

bool is_flagged(const IntervalValue& value) {
    return value.maybe_discontinuous || value.maybe_undefined;
}

bool is_exact_zero(const Interval& x) {
    return x.lo == 0.0 && x.hi == 0.0;
}

/// f is zero everywhere on the cell.
bool is_zero_region(const IntervalGradient& enclosure, double center_value) {
    if (is_flagged(enclosure.value)) return false;
    if (is_exact_zero(enclosure.value.value)) return true;
    return center_value == 0.0 && is_exact_zero(enclosure.gradient[0]) &&
           is_exact_zero(enclosure.gradient[1]) && is_exact_zero(enclosure.gradient[2]);
}

/// f is smooth on the cell and its gradient enclosure contains 0.
bool may_hide_feature(const IntervalGradient& enclosure) {
    if (is_flagged(enclosure.value)) return false;
    return std::all_of(std::begin(enclosure.gradient), std::end(enclosure.gradient),
                       [](const Interval& g) { return g.contains(0.0); });
}

/// Classifies cells one level at a time; walks each cell's ancestors with push/pop.
class CellClassifier {
  public:
    /// Values in `known` and root counts in `known_edges` (either may be null) are not evaluated
    /// again; those it evaluates are kept (corners(), edges()).
    CellClassifier(Evaluator& evaluator, const Lattice& lattice, const OctreeSettings& settings,
                   const ValueMap* known, const EdgeRootCounts* known_edges = nullptr)
        : evaluator_(evaluator),
          lattice_(lattice),
          settings_(settings),
          known_edges_(known_edges),
          corners_(evaluator, lattice, known),
          path_(evaluator, lattice) {}

    CellClassifier(const CellClassifier&) = delete;
    CellClassifier& operator=(const CellClassifier&) = delete;

    /// Classifies cells (one level, in octree order), the children of one parent together, until
    /// the budget is exhausted; returns how many were classified.
    std::size_t classify(std::span<const CellId> cells, std::span<CellOutcome> out,
                         const WorkBudget& budget) {
        std::size_t done = 0;
        while (done < cells.size()) {
            if (budget.exhausted()) break;
            std::size_t end = done + 1;
            while (end < cells.size() && cells[end].parent() == cells[done].parent()) ++end;
            if (cells[done].depth > 0) path_.walk_to(cells[done].parent());
            const std::size_t classified =
                classify_siblings(cells.subspan(done, end - done), out.subspan(done, end - done),
                                  [&budget] { return budget.exhausted(); });
            done += classified;
            if (done < end) break;
        }
        return done;
    }

    /// The 8 children of `cell`, with the evaluator already specialised to it, their enclosures
    /// in one batch; stops early (leaving the rest Empty) when the budget is cancelled.
    std::array<CellOutcome, 8> classify_children(const CellId& cell, const WorkBudget& budget) {
        std::array<CellId, 8> children;
        for (int octant = 0; octant < 8; ++octant) children[octant] = cell.child(octant);
        std::array<CellOutcome, 8> out;
        out.fill(CellOutcome::Empty);
        classify_siblings(children, out, [&budget] { return budget.cancelled(); });
        return out;
    }

    CornerCache& corners() { return corners_; }
    EdgeRootCounts& edges() { return edges_; }

  private:
    /// The siblings' enclosures in one batch, then each one's outcome; stops (returning how many
    /// were classified, at least one) when `stop()` says so.
    template <class Stop>
    std::size_t classify_siblings(std::span<const CellId> cells, std::span<CellOutcome> out,
                                  const Stop& stop) {
        boxes_.clear();
        for (const CellId& cell : cells) boxes_.push_back(lattice_.cell_box(cell));
        if (cells.front().depth < settings_.min_depth) {
            values_.resize(cells.size());
            evaluator_.intervals(boxes_, values_);
            for (std::size_t i = 0; i < cells.size(); ++i) out[i] = coarse_outcome(values_[i]);
            return cells.size();
        }
        enclosures_.resize(cells.size());
        evaluator_.interval_gradients(boxes_, enclosures_);
        prefetch_corners(cells);
        for (std::size_t i = 0; i < cells.size(); ++i) {
            if (i > 0 && stop()) return i;
            out[i] = outcome(cells[i], enclosures_[i]);
        }
        return cells.size();
    }

    /// The corners and centres of the siblings whose enclosure of f holds 0 (most of them
    /// need those values next: the mean value form, the edges, the feature search; the mesher the
    /// corners of every leaf), evaluated in one batch rather than one by one.
    void prefetch_corners(std::span<const CellId> cells) {
        points_.clear();
        for (std::size_t i = 0; i < cells.size(); ++i) {
            if (enclosures_[i].value.value.excludes_zero()) continue;
            for (int c = 0; c < 8; ++c) points_.push_back(lattice_.corner(cells[i], c));
            if (cells[i].depth < lattice_.max_depth())
                points_.push_back(lattice_.origin(cells[i]) +
                                  glm::u32vec3(lattice_.span(cells[i].depth) / 2));
        }
        corners_.prefetch(points_);
    }

    static CellOutcome coarse_outcome(const IntervalValue& value) {
        if (value.value.excludes_zero()) return CellOutcome::Empty;
        if (!is_flagged(value) && is_exact_zero(value.value)) return CellOutcome::Region;
        return CellOutcome::Split;
    }

    /// f at the cell's centre: a lattice point (a corner of the children) unless the cell is on
    /// the finest lattice.
    double center_value(const CellId& cell, const Box& box) {
        if (cell.depth >= lattice_.max_depth()) return evaluator_.value(box.center());
        return corners_.value(lattice_.origin(cell) + glm::u32vec3(lattice_.span(cell.depth) / 2));
    }

    CellOutcome outcome(const CellId& cell, const IntervalGradient& enclosure) {
        if (enclosure.value.value.excludes_zero()) return CellOutcome::Empty;
        const Box box = lattice_.cell_box(cell);
        if (!is_flagged(enclosure.value)) {
            const double center = center_value(cell, box);
            if (is_zero_region(enclosure, center)) return CellOutcome::Region;
            if (mean_value_excludes_zero(enclosure, center, box)) return CellOutcome::Empty;
        }
        const int bisections =
            std::max(settings_.max_depth, cell.depth) - cell.depth + kSubLatticeBisections;
        switch (classify_cell(evaluator_, corners_, lattice_, cell, enclosure, bisections,
                              {known_edges_, &edges_})) {
            case CellVerdict::Empty:
                return CellOutcome::Empty;
            case CellVerdict::Leaf:
                return CellOutcome::Leaf;
            case CellVerdict::Split:
                break;
        }
        if (cell.depth < settings_.max_depth) return CellOutcome::Split;
        if (cell.depth >= settings_.feature_depth || !may_hide_feature(enclosure))
            return CellOutcome::Unresolved;
        // A component Marching Cubes would not see: all corners on one side and an extremum of f
        // inside. Below max_depth, in the subtree of such a cell, also the cells its surface
        // crosses, until they are proven.
        const bool agree = corners_agree(cell);
        if (!agree && cell.depth == settings_.max_depth) return CellOutcome::Unresolved;
        return !agree || extremum_inside(cell) ? CellOutcome::Split : CellOutcome::Unresolved;
    }

    /// All corners of `cell` are on one side: Marching Cubes sees nothing there, so whatever
    /// surface it holds would be lost.
    bool corners_agree(const CellId& cell) {
        const bool inside = is_inside(corners_.value(lattice_.corner(cell, 0)));
        for (int c = 1; c < 8; ++c)
            if (is_inside(corners_.value(lattice_.corner(cell, c))) != inside) return false;
        return true;
    }

    /// The gradient at every corner of `cell` points away from its centre (corners outside:
    /// a minimum of f is likely inside, the centre of a bubble) or towards it (inside: a
    /// maximum, a hollow). Where an interval enclosure of the gradient merely fails to exclude 0
    /// (on a CAD model's blends and creases), the corners' gradients do not all point so, and
    /// splitting deeper would find nothing.
    bool extremum_inside(const CellId& cell) {
        const Box box = lattice_.cell_box(cell);
        const glm::dvec3 center = box.center();
        std::array<double, 8> x, y, z;
        for (int c = 0; c < 8; ++c) {
            const glm::dvec3 p = lattice_.point(lattice_.corner(cell, c));
            x[c] = p.x;
            y[c] = p.y;
            z[c] = p.z;
        }
        std::array<ValueGradient, 8> g;
        evaluator_.value_gradients({x, y, z}, g);
        const double side = is_inside(g[0].value) ? -1.0 : 1.0;
        for (int c = 0; c < 8; ++c) {
            const glm::dvec3 out = glm::dvec3(x[c], y[c], z[c]) - center;
            if (!(side * glm::dot(g[c].gradient, out) > 0.0)) return false;
        }
        return true;
    }

    Evaluator& evaluator_;
    const Lattice& lattice_;
    const OctreeSettings& settings_;
    const EdgeRootCounts* known_edges_;
    CornerCache corners_;
    // Of the cells classified (siblings and neighbouring families share edges), beyond those in
    // known_edges_.
    EdgeRootCounts edges_;
    AncestorPath path_;  // to the parent of the siblings being classified
    std::vector<Box> boxes_;
    std::vector<glm::u32vec3> points_;
    std::vector<IntervalValue> values_;
    std::vector<IntervalGradient> enclosures_;
};

/// Runs of consecutive cells for the workers, cut where the parent changes once a run is long
/// enough, so that the children of one parent are classified together.
std::vector<std::pair<std::size_t, std::size_t>> task_ranges(std::span<const CellId> cells) {
    std::vector<std::pair<std::size_t, std::size_t>> ranges;
    std::size_t begin = 0;
    for (std::size_t i = 1; i <= cells.size(); ++i) {
        const bool end = i == cells.size();
        if (end || (i - begin >= kCellsPerTask && cells[i].parent() != cells[i - 1].parent())) {
            ranges.emplace_back(begin, i);
            begin = i;
        }
    }
    return ranges;
}

}  // namespace

void PendingCells::add(const CellId& cell) {
    next_.push_back(level_order_key(cell));
    ++size_;
}

void PendingCells::take_front(std::size_t n, std::vector<CellId>& out) {
    if (cursor_ == level_.size()) {
        // The level is done: the next one, made in the order its parents were classified
        // (mostly octree order already), becomes the level in octree order.
        level_.swap(next_);
        next_.clear();
        cursor_ = 0;
        std::sort(level_.begin(), level_.end());
    }
    const std::size_t end = std::min(level_.size(), cursor_ + n);
    for (; cursor_ < end; ++cursor_) out.push_back(cell_of_level_order_key(level_[cursor_]));
}

void PendingCells::return_front(std::span<const CellId> cells) {
    assert(cells.size() <= cursor_);
    cursor_ -= cells.size();
    for (std::size_t i = 0; i < cells.size(); ++i) level_[cursor_ + i] = level_order_key(cells[i]);
}

std::vector<CellId> PendingCells::cells() const {
    std::vector<CellId> out;
    out.reserve(size_);
    for (std::size_t i = cursor_; i < level_.size(); ++i)
        out.push_back(cell_of_level_order_key(level_[i]));
    std::vector<std::uint64_t> next = next_;
    std::sort(next.begin(), next.end());
    for (std::uint64_t key : next) out.push_back(cell_of_level_order_key(key));
    return out;
}

void PendingCells::clear() {
    level_.clear();
    next_.clear();
    cursor_ = 0;
    size_ = 0;
}

Octree::Octree(const Lattice& lattice, const OctreeSettings& settings)
    : lattice_(lattice), settings_(settings) {
    assert(lattice.max_depth() == kMaxOctreeDepth);
    assert(0 <= settings.min_depth && settings.min_depth <= settings.max_depth &&
           settings.max_depth <= settings.feature_depth &&
           settings.feature_depth <= kMaxOctreeDepth);
    pending_.add(CellId{});
    counts_.pending = 1;
}

void Octree::advance(EvaluatorPool& pool, ValueMap& values, const WorkBudget& budget,
                     std::size_t max_frontier) {
    std::vector<CellId> round;
    std::vector<CellId> fresh;  // the round's cells not classified ahead before
    while (!pending_.empty() && !found_region() && !budget.exhausted()) {
        const std::size_t frontier = pending_.size() + settled_.size();
        if (frontier >= max_frontier) break;
        // The next cells of the shallowest pending level: as many as may be split (into 8 each)
        // without passing max_frontier.
        const std::size_t room = std::min(kCellsPerRound, (max_frontier - frontier) / 7 + 1);
        round.clear();
        pending_.take_front(room, round);
        fresh.clear();
        for (const CellId& cell : round) {
            if (!ahead_.contains(level_order_key(cell))) fresh.push_back(cell);
        }
        if (round.front().depth != edge_counts_depth_) {
            // Edges of cells at one depth are shared only with cells at that depth.
            edge_counts_.clear();
            edge_counts_depth_ = round.front().depth;
        }
        const std::vector<std::optional<CellOutcome>> outcomes =
            classify_round(pool, values, fresh, budget);
        apply_in_order(round, outcomes);
        counts_.pending = pending_.size();
    }
}

std::vector<std::optional<CellOutcome>> Octree::classify_round(EvaluatorPool& pool,
                                                               ValueMap& values,
                                                               std::span<const CellId> cells,
                                                               const WorkBudget& budget) {
    const auto ranges = task_ranges(cells);
    std::vector<CellOutcome> outcomes(cells.size());
    std::vector<std::size_t> classified(ranges.size(), 0);
    std::vector<ValueMap> evaluated(ranges.size());
    std::vector<EdgeRootCounts> counted(ranges.size());
    pool.for_each(ranges.size(), [&](std::size_t task, CountingEvaluator& evaluator) {
        const auto [begin, end] = ranges[task];
        CellClassifier classifier(evaluator, lattice_, settings_, &values, &edge_counts_);
        classified[task] =
            classifier.classify(cells.subspan(begin, end - begin),
                                std::span(outcomes).subspan(begin, end - begin), budget);
        evaluated[task] = std::move(classifier.corners().values());
        counted[task] = std::move(classifier.edges());
    });
    std::vector<std::optional<CellOutcome>> out(cells.size());
    for (std::size_t task = 0; task < ranges.size(); ++task) {
        const auto [begin, end] = ranges[task];
        for (std::size_t i = begin; i < begin + classified[task]; ++i) out[i] = outcomes[i];
        values.merge(evaluated[task]);
        edge_counts_.merge(counted[task]);
    }
    return out;
}

void Octree::apply_in_order(std::span<const CellId> round,
                            std::span<const std::optional<CellOutcome>> outcomes) {
    // Applied in octree order, whatever the workers' timing, so that the frontier does not depend
    // on it: apply's caps (feature_room, max_cells) count cells in this order. A budget may cut
    // one task short while another worker classified cells after it: those wait in ahead_ for
    // the cells before them (classifying them again would throw a helper's work away).
    std::vector<CellId> left;  // not applied: budget exhausted
    std::size_t next_fresh = 0;
    for (const CellId& cell : round) {
        const std::uint64_t key = level_order_key(cell);
        std::optional<CellOutcome> outcome;
        const auto known = ahead_.find(key);
        if (known != ahead_.end()) {
            outcome = known->second;
        } else {
            assert(next_fresh < outcomes.size());  // the cells not in ahead_, in order
            outcome = outcomes[next_fresh++];
        }
        if (left.empty() && outcome) {
            if (known != ahead_.end()) ahead_.erase(known);
            pending_.classified();
            apply(cell, *outcome);
            continue;
        }
        if (outcome) ahead_.emplace(key, *outcome);
        left.push_back(cell);
    }
    pending_.return_front(left);
}

void Octree::apply(const CellId& cell, CellOutcome outcome) {
    ++counts_.classified;
    counts_.at_max_depth += cell.depth == settings_.max_depth;
    counts_.depth = std::max(counts_.depth, cell.depth);
    switch (outcome) {
        case CellOutcome::Empty:
            return;
        case CellOutcome::Region:
            ++counts_.regions;
            return;
        case CellOutcome::Leaf:
            settled_.push_back({cell, CellState::Leaf});
            ++counts_.leaves;
            return;
        case CellOutcome::Split:
            if (pending_.size() + settled_.size() + 8 <= settings_.max_cells &&
                feature_room(cell)) {
                for (int octant = 0; octant < 8; ++octant) pending_.add(cell.child(octant));
                return;
            }
            ++counts_.capped;
            [[fallthrough]];
        case CellOutcome::Unresolved:
            settled_.push_back({cell, CellState::Unresolved});
            ++counts_.unresolved;
            return;
    }
}

bool Octree::feature_room(const CellId& cell) {
    if (cell.depth < settings_.max_depth) {
        return true;
    }
    // The search for features below max_depth may cost at most an eighth of the work above it
    // (the cells classified at max_depth, counted in level order, so the same whatever the
    // slicing): a model whose enclosures are loose everywhere must not spend its time there.
    constexpr std::size_t kLeastFeatureCells = 4096;
    const std::size_t allowed = std::max(kLeastFeatureCells, counts_.at_max_depth / 8);
    if (feature_cells_ + 8 > allowed) return false;
    feature_cells_ += 8;
    return true;
}

void Octree::settle_pending() {
    for (const CellId& cell : pending_.cells()) {
        settled_.push_back({cell, CellState::Unresolved});
        ++counts_.unresolved;
    }
    pending_.clear();
    ahead_.clear();
    counts_.pending = 0;
}

std::vector<FrontierCell> Octree::frontier() const {
    std::vector<FrontierCell> cells = settled_;
    for (const CellId& cell : pending_.cells()) cells.push_back({cell});
    std::sort(cells.begin(), cells.end(), [&](const FrontierCell& a, const FrontierCell& b) {
        return lattice_.octree_order(a.cell) < lattice_.octree_order(b.cell);
    });
    return cells;
}

std::vector<FrontierCell> coarsened(std::vector<FrontierCell> frontier, std::size_t max_cells) {
    std::vector<FrontierCell> merged;
    while (frontier.size() > max_cells) {
        int deepest = 0;
        for (const FrontierCell& f : frontier) deepest = std::max(deepest, f.cell.depth);
        if (deepest <= 1) break;
        // The children of one parent are consecutive in octree order (the frontier holds no
        // cell deeper than them), and the parent's order is its first child's origin's.
        merged.clear();
        for (const FrontierCell& f : frontier) {
            if (f.cell.depth < deepest) {
                merged.push_back(f);
            } else if (merged.empty() || merged.back().cell != f.cell.parent()) {
                merged.push_back({f.cell.parent(), CellState::Pending});
            }
        }
        // Not fewer cells where each parent held one (the rest empty), but one level less: the
        // loop ends.
        assert(merged.size() <= frontier.size());
        frontier.swap(merged);
    }
    return frontier;
}

namespace {

/// Depth-first classification of a subtree (split_settled): down to max_depth, as the octree
/// does; from there on, a cell to split stays unresolved. The search for small features below
/// max_depth is the octree's, within its share of the work (Octree::feature_room); the mesh
/// builder's splits only match finer neighbours, one level at a time, and never go deeper than
/// the octree did. Searching again from every split cell, with no share to stop it, followed a
/// CAD model's whole surface down to feature_depth as the grading spread from cell to cell
/// (bear.vm at depth 5: 114,663 cells, 73,075 of them at depth 8, and 6.2 s, instead of 5,344
/// cells and 0.25 s).
void classify_subtree(Evaluator& evaluator, CellClassifier& classifier, const Lattice& lattice,
                      const OctreeSettings& settings, const CellId& cell,
                      std::vector<FrontierCell>& out, const WorkBudget& budget) {
    evaluator.push(lattice.cell_box(cell));
    const std::array<CellOutcome, 8> outcomes = classifier.classify_children(cell, budget);
    for (int octant = 0; octant < 8 && !budget.cancelled(); ++octant) {
        const CellId child = cell.child(octant);
        switch (outcomes[octant]) {
            case CellOutcome::Empty:
            case CellOutcome::Region:
                break;
            case CellOutcome::Leaf:
                out.push_back({child, CellState::Leaf});
                break;
            case CellOutcome::Unresolved:
                out.push_back({child, CellState::Unresolved});
                break;
            case CellOutcome::Split:
                if (child.depth >= settings.max_depth) {
                    out.push_back({child, CellState::Unresolved});
                } else {
                    classify_subtree(evaluator, classifier, lattice, settings, child, out, budget);
                }
                break;
        }
    }
    evaluator.pop();
}

}  // namespace

std::vector<FrontierCell> split_settled(Evaluator& evaluator, const Lattice& lattice,
                                        const OctreeSettings& settings, const CellId& cell,
                                        const ValueMap& known, ValueMap& evaluated,
                                        const WorkBudget& budget) {
    assert(cell.depth < lattice.max_depth());
    std::vector<FrontierCell> out;
    {
        CellClassifier classifier(evaluator, lattice, settings, &known);
        classify_subtree(evaluator, classifier, lattice, settings, cell, out, budget);
        for (auto& [key, value] : classifier.corners().values()) evaluated.emplace(key, value);
    }
    return out;
}

}  // namespace isomesh
