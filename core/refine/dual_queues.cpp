// Which operation comes next (ROAM's dual-queue loop, Duchaineau et al. 1997, section 5): split
// while the constraint wants detail, never past it (a forced chain counts in full); merge while the
// mesh stays detailed enough without the merge, or breaks a cap; otherwise exchange cheap merges
// for a split worth swap_ratio times more.
#include <algorithm>

#include "refine/refiner_impl.h"

namespace isomesh {

using namespace refiner_detail;

// ---------------------------------------------------------------------------------------------
// Choosing operations

bool Refiner::Impl::acceptable_split(const MeshStats& stats, const SplitPlan& plan) const {
    // Never overshoot: the constraint must still want refinement just before the last bisection
    // of the chain, and the mesh after it must not break a cap.
    MeshStats before_last = stats;
    before_last.triangles += plan.added_triangles - 1;
    MeshStats after = stats;
    after.triangles += plan.added_triangles;
    return constraint_.wants_refinement(before_last) && !constraint_.over_limit(after);
}

bool Refiner::Impl::conflicts(const SplitPlan& plan, std::uint32_t record) const {
    if (record == kNone) return false;
    const auto& children = records_[record].children;
    auto is_child = [&](std::uint32_t t) {
        return t != kNone && std::find(children.begin(), children.end(), t) != children.end();
    };
    return is_child(plan.partner) || std::any_of(plan.chain.begin(), plan.chain.end(), is_child);
}

bool Refiner::Impl::find_split(const MeshStats& stats, SplitPlan& plan) {
    // Quick refusals before scanning the queue: a split adds at least 1 triangle, and at least 2
    // on a closed mesh.
    SplitPlan smallest;
    smallest.added_triangles = has_boundary_ ? 1 : 2;
    if (!acceptable_split(stats, smallest)) return false;
    // The common case: the top of the queue fits. A triangle whose forced splits meet one that
    // cannot be split (no vertex for it, too small) cannot be split either: it leaves the queue
    // (until the function changes), or every search would walk its chain again.
    std::uint32_t top = split_queue_->top();
    while (top != kNone && !plan_split(top, plan)) {
        block(top);
        top = split_queue_->top();
    }
    if (top == kNone) return false;
    if (acceptable_split(stats, plan)) return true;
    bool found = false;
    unplannable_.clear();
    split_queue_->visit_in_order([&](std::uint32_t t) {
        if (!plan_split(t, plan)) {
            unplannable_.push_back(t);
            return false;
        }
        found = acceptable_split(stats, plan);
        return found;
    });
    for (std::uint32_t t : unplannable_) block(t);
    return found;
}

bool Refiner::Impl::choose_merges(const MeshStats& stats, const SplitPlan& plan, double below) {
    // The cheapest merges (each worth less than `below`) that make room for the split.
    constexpr std::size_t kMaxMerges = 8;
    exchange_merges_.clear();
    MeshStats after = stats;
    bool enough = false;
    int skipped = 0;
    merge_queue_->visit_in_order([&](std::uint32_t record) {
        if (exchange_merges_.size() == kMaxMerges) return true;
        // Bucket order is approximate: look a little past a record that is too dear.
        if (!(merge_queue_->priority(record) < below)) return ++skipped > int(kMaxMerges);
        if (conflicts(plan, record)) return false;
        after = stats_after_merge(after, record);
        exchange_merges_.push_back(record);
        enough = acceptable_split(after, plan);
        return enough;
    });
    return enough;
}

std::size_t Refiner::Impl::try_exchange(const MeshStats& stats) {
    // ROAM's optimisation at a fixed budget: undo the cheapest splits to make room for a better
    // one, when it is worth swap_ratio times more than each split undone. The best few splits are
    // tried, as a long forced chain may need more room than the cheap merges give.
    const std::uint32_t cheapest = merge_queue_->top();
    if (cheapest == kNone) return 0;
    const double threshold = settings_.swap_ratio * merge_queue_->priority(cheapest);
    constexpr int kCandidates = 16;
    int examined = 0;
    bool found = false;
    split_queue_->visit_in_order([&](std::uint32_t t) {
        if (++examined > kCandidates) return true;
        const double priority = split_queue_->priority(t);
        if (!(priority > threshold)) return false;  // bucket order is approximate: look further
        found =
            plan_split(t, plan_) && choose_merges(stats, plan_, priority / settings_.swap_ratio);
        return found;
    });
    if (!found) return 0;
    if (!prepare(plan_)) return 1;
    for (std::uint32_t record : exchange_merges_) merge(record);
    execute(plan_);
    ++counters_.swaps;
    return exchange_merges_.size() + plan_.bisections();
}

std::size_t Refiner::Impl::act() {
    const MeshStats current = constraint_stats();
    if (constraint_.wants_refinement(current) && find_split(current, plan_)) {
        if (!prepare(plan_)) return 1;  // no vertex for it: another split next time
        execute(plan_);
        return plan_.bisections();
    }
    const std::uint32_t record = merge_queue_->top();
    if (record == kNone) return 0;
    if (constraint_.over_limit(current) ||
        !constraint_.wants_refinement(stats_after_merge(current, record))) {
        merge(record);
        return 1;
    }
    return try_exchange(current);
}

}  // namespace isomesh
