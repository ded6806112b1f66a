// The refiner's view of errors: base midpoint projections (the vertex a split would create,
// shared by the two triangles of a diamond), errors brought up to the current function version in
// batches, and the queue entries and running totals of the leaves.
#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>

#include "refine/refiner_impl.h"

namespace isomesh {

using namespace refiner_detail;

// ---------------------------------------------------------------------------------------------
// Errors and queues

glm::dvec3 Refiner::Impl::candidate_direction(std::uint32_t t) const {
    const Triangle& T = triangles_[t];
    return vertices_[T.v[T.base]].normal + vertices_[T.v[(T.base + 1) % 3]].normal;
}

ProjectionRequest Refiner::Impl::candidate_request(std::uint32_t t) const {
    const Triangle& T = triangles_[t];
    const Vertex& a = vertices_[T.v[T.base]];
    const Vertex& b = vertices_[T.v[(T.base + 1) % 3]];
    // Symmetric in a and b, so that both triangles of a diamond compute the same point.
    ProjectionRequest request;
    request.start = 0.5 * (a.position + b.position);
    request.direction = a.normal + b.normal;  // candidate_direction
    request.slope = 0.5 * (a.gradient_norm + b.gradient_norm);
    request.scale = glm::length(b.position - a.position);
    request.fixed_axes = T.nb[T.base] == kNone ? face_axes(a.position, b.position, bounds_) : 0;
    if (!(request.scale > 0.0)) request.scale = settings_.min_edge_length;
    if (T.midpoint_value_known && T.error_version == version_)
        request.start_value = T.candidate_gradient_norm;
    return request;
}

void Refiner::Impl::ensure_candidates(std::span<const std::uint32_t> tris, bool look_ahead) {
    pending_.clear();
    requests_.clear();
    for (std::uint32_t t : tris) {
        Triangle& T = triangles_[t];
        if (T.candidate_version == version_) continue;
        const std::uint32_t n = T.nb[T.base];
        if (is_diamond(t, n) && triangles_[n].candidate_version == version_) {
            const Triangle& N = triangles_[n];  // the diamond partner's is the same point
            T.candidate = N.candidate;
            T.candidate_normal = N.candidate_normal;
            T.candidate_gradient_norm = N.candidate_gradient_norm;
            T.candidate_on_surface = N.candidate_on_surface;
            T.candidate_refused = N.candidate_refused;
            T.candidate_retried = N.candidate_retried;
            T.candidate_version = version_;
            T.midpoint_value_known = false;
            continue;
        }
        if (AheadProjection* a = projected_ahead(t)) {
            set_candidate(t, a->projection, candidate_direction(t));
            a->slot = kNone;  // used
            continue;
        }
        pending_.push_back(t);
        requests_.push_back(candidate_request(t));
    }
    if (pending_.empty()) return;
    ahead_pending_.clear();
    ++ahead_batch_;
    if (look_ahead) request_ahead();
    projections_.resize(requests_.size());
    project_to_surface(*evaluator_, requests_, projections_, settings_.projection);
    for (std::size_t i = 0; i < pending_.size(); ++i)
        set_candidate(pending_[i], projections_[i], requests_[i].direction);
    std::size_t entry = 0;
    for (std::size_t k = 0; k < ahead_pending_.size(); ++k) {
        while (!free_ahead(ahead_[entry])) ++entry;
        const std::uint32_t t = ahead_pending_[k];
        // The base neighbour, prefetched with t, has arrived meanwhile: now its own neighbours.
        if (const std::uint32_t n = triangles_[t].nb[triangles_[t].base]; n != kNone)
            prefetch_split(n);
        ahead_[entry] = {t, triangles_[t].id, version_, ahead_batch_,
                         projections_[pending_.size() + k]};
    }
}

bool Refiner::Impl::free_ahead(const AheadProjection& a) const {
    // Used, outdated, or for a triangle split without it (as a diamond partner) or still
    // waiting after several batches (the queue's order changed): no longer worth keeping.
    if (a.slot == kNone || a.slot >= triangles_.size() || a.version != version_ ||
        ahead_batch_ - a.batch > kAheadBatches)
        return true;
    const Triangle& T = triangles_[a.slot];
    return T.id != a.id || T.state != TriangleState::Leaf || T.candidate_version == version_;
}

void Refiner::Impl::set_candidate(std::uint32_t t, const Projection& p,
                                  const glm::dvec3& direction) {
    Triangle& T = triangles_[t];
    T.candidate = p.position;
    T.candidate_normal = p.on_surface() ? p.normal : unit_or_zero(direction);
    T.candidate_gradient_norm = p.gradient_norm;
    T.candidate_on_surface = p.on_surface();
    T.candidate_refused = !p.on_surface() || !settings_.box.contains(p.position);
    T.candidate_retried = false;
    T.candidate_version = version_;
    T.midpoint_value_known = false;
}

void Refiner::Impl::request_ahead() {
    // The leaves after the top that will want a projection: not current, no current diamond
    // partner to copy from, not asked for already (nor their partners: the same point).
    const auto wanted = [&](std::uint32_t t) {
        const Triangle& T = triangles_[t];
        if (T.candidate_version == version_ || projected_ahead(t)) return false;
        const std::uint32_t n = T.nb[T.base];
        const bool diamond = is_diamond(t, n);
        if (diamond && triangles_[n].candidate_version == version_) return false;
        for (const auto* list : {&pending_, &ahead_pending_})
            for (std::uint32_t u : *list)
                if (u == t || (diamond && u == n)) return false;
        return true;
    };
    const auto room = static_cast<std::size_t>(std::count_if(
        ahead_.begin(), ahead_.end(), [&](const AheadProjection& a) { return free_ahead(a); }));
    if (room == 0) return;
    // The leaves to look at, far apart in memory: asked for together (then their base
    // neighbours), so that their cache misses overlap instead of following one another.
    std::array<std::uint32_t, 2 * kProjectedAhead> next;
    std::size_t count = 0;
    split_queue_->visit_in_order([&](std::uint32_t t) {
        // Both lines of the slot: candidate_request reads the midpoint value kept in the second
        // (perf: three quarters of candidate_request's time waited for that load).
        __builtin_prefetch(&triangles_[t]);
        __builtin_prefetch(&triangles_[t].candidate_gradient_norm);
        next[count++] = t;
        return count == next.size();
    });
    for (std::size_t i = 0; i < count; ++i) {
        const Triangle& T = triangles_[next[i]];
        if (T.nb[T.base] != kNone) __builtin_prefetch(&triangles_[T.nb[T.base]]);
        if (T.candidate_version != version_) {  // the base's ends, for candidate_request
            __builtin_prefetch(&vertices_[T.v[T.base]]);
            __builtin_prefetch(&vertices_[T.v[(T.base + 1) % 3]]);
        }
    }
    for (std::size_t i = 0; i < count && ahead_pending_.size() < room; ++i) {
        // t, then the base neighbour its split will force first when they are no diamond.
        const std::uint32_t t = next[i];
        for (std::uint32_t u = t; u != kNone && ahead_pending_.size() < room && wanted(u);) {
            ahead_pending_.push_back(u);
            requests_.push_back(candidate_request(u));
            prefetch_split(u);
            const std::uint32_t n = triangles_[u].nb[triangles_[u].base];
            u = u == t && !is_diamond(u, n) ? n : kNone;
        }
    }
}

void Refiner::Impl::prefetch_split(std::uint32_t t) const {
    // What planning and bisecting t will read or write, in the order of its splits to come: its
    // neighbours (the base neighbour is bisected with it, the others get new neighbours), its
    // apex, its candidate (the second cache line) and its split record's parent.
    const Triangle& T = triangles_[t];
    for (std::uint32_t n : T.nb)
        if (n != kNone) __builtin_prefetch(&triangles_[n], 1);
    __builtin_prefetch(&vertices_[T.v[(T.base + 2) % 3]]);
    __builtin_prefetch(&T.candidate, 1);
    if (T.parent != kNone) __builtin_prefetch(&records_[T.parent], 1);
}

Refiner::Impl::AheadProjection* Refiner::Impl::projected_ahead(std::uint32_t t) {
    for (AheadProjection& a : ahead_)
        if (a.slot == t && a.id == triangles_[t].id && a.version == version_) return &a;
    return nullptr;
}

void Refiner::Impl::geometry(std::uint32_t t, bool with_midpoint, TriangleGeometry& out) const {
    const Triangle& T = triangles_[t];
    double gradient_norm = 0.0;  // the mean over the corners, or 0 if one is unknown
    for (std::uint32_t v : T.v) {
        const double g = vertices_[v].gradient_norm;
        gradient_norm = g > 0.0 && gradient_norm >= 0.0 ? gradient_norm + g / 3.0 : -1.0;
    }
    out.a = position(t, T.base);
    out.b = position(t, T.base + 1);
    out.c = position(t, T.base + 2);
    out.projected_midpoint = !with_midpoint ? glm::dvec3(0.0)
                             : T.state == TriangleState::Split
                                 ? vertices_[records_[T.split].vertex].position
                                 : T.candidate;
    out.gradient_norm = std::max(gradient_norm, 0.0);
}

void Refiner::Impl::ensure_errors(std::span<const std::uint32_t> tris) {
    stale_.clear();
    for (std::uint32_t t : tris)
        if (triangles_[t].error_version != version_) stale_.push_back(t);
    if (stale_.empty()) return;
    // The base midpoint is projected here only for measures that read it; otherwise only when
    // the triangle is split.
    const bool with_midpoint = settings_.error_measure->needs_projected_midpoint();
    if (with_midpoint) {
        std::vector<std::uint32_t> leaves;
        for (std::uint32_t t : stale_)
            if (triangles_[t].state != TriangleState::Split) leaves.push_back(t);
        ensure_candidates(leaves);
    }
    geometries_.resize(stale_.size());
    for (std::size_t i = 0; i < stale_.size(); ++i)
        geometry(stale_[i], with_midpoint, geometries_[i]);
    errors_.resize(stale_.size());
    midpoint_values_.resize(stale_.size());
    settings_.error_measure->errors_and_midpoint_values(*evaluator_, geometries_, errors_,
                                                        midpoint_values_);
    for (std::size_t i = 0; i < stale_.size(); ++i) {
        Triangle& T = triangles_[stale_[i]];
        T.error = errors_[i] >= 0.0 ? errors_[i] : 0.0;  // NaN or negative from a custom measure
        T.error_version = version_;
        // Kept for the projection of the base midpoint, in the candidate's place until then.
        if (T.state != TriangleState::Split && T.candidate_version != version_ &&
            !std::isnan(midpoint_values_[i])) {
            T.candidate_gradient_norm = midpoint_values_[i];
            T.midpoint_value_known = true;
        }
    }
}

void Refiner::Impl::add_leaf(std::uint32_t t) {
    Triangle& T = triangles_[t];
    T.state = TriangleState::Leaf;
    T.split = kNone;
    ++leaf_count_;
    assert(T.error_version == version_);
    const double error = T.error;
    total_error_.add(error);
    PriorityQueue& queue = splittable(t) ? *split_queue_ : *blocked_queue_;
    queue.insert(t, error);
    delta_.add_triangle(T.id, t);
}

void Refiner::Impl::remove_leaf(std::uint32_t t) {
    const Triangle& T = triangles_[t];
    assert(T.state == TriangleState::Leaf);
    if (split_queue_->contains(t))
        split_queue_->remove(t);
    else
        blocked_queue_->remove(t);
    total_error_.add(-T.error);
    --leaf_count_;
    delta_.remove_triangle(T.id);
}

double Refiner::Impl::parent_error(std::uint32_t parent) {
    ensure_errors({&parent, 1});
    return triangles_[parent].error;
}

double Refiner::Impl::merge_priority(std::uint32_t record) {
    const SplitRecord& R = records_[record];
    const std::size_t n = R.parents[1] == kNone ? 1 : 2;
    ensure_errors({R.parents.data(), n});
    double priority = triangles_[R.parents[0]].error;
    if (n == 2) priority = std::max(priority, triangles_[R.parents[1]].error);
    return priority;
}

void Refiner::Impl::child_became_leaf(std::uint32_t record) {
    if (record == kNone) return;
    SplitRecord& R = records_[record];
    assert(R.split_children > 0);
    if (--R.split_children == 0) merge_queue_->insert(record, merge_priority(record));
}

void Refiner::Impl::child_was_split(std::uint32_t record) {
    if (record == kNone) return;
    SplitRecord& R = records_[record];
    if (R.split_children++ == 0) merge_queue_->remove(record);
}

}  // namespace isomesh
