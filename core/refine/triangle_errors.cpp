// The refiner's view of errors: base midpoint projections (the vertex a split would create,
// shared by the two triangles of a diamond), errors brought up to the current function version in
// batches, and the queue entries and running totals of the leaves.
#include <algorithm>
#include <cassert>

#include "refine/refiner_impl.h"

namespace isomesh {

using namespace refiner_detail;

// ---------------------------------------------------------------------------------------------
// Errors and queues

ProjectionRequest Refiner::Impl::candidate_request(std::uint32_t t) const {
    const Triangle& T = triangles_[t];
    const Vertex& a = vertices_[T.v[T.base]];
    const Vertex& b = vertices_[T.v[(T.base + 1) % 3]];
    // Symmetric in a and b, so that both triangles of a diamond compute the same point.
    ProjectionRequest request;
    request.start = 0.5 * (a.position + b.position);
    request.direction = a.normal + b.normal;
    request.slope = 0.5 * (a.gradient_norm + b.gradient_norm);
    request.scale = glm::length(b.position - a.position);
    request.fixed_axes = T.nb[T.base] == kNone ? face_axes(a.position, b.position, bounds_) : 0;
    if (!(request.scale > 0.0)) request.scale = settings_.min_edge_length;
    return request;
}

void Refiner::Impl::ensure_candidates(std::span<const std::uint32_t> tris) {
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
            continue;
        }
        pending_.push_back(t);
        requests_.push_back(candidate_request(t));
    }
    projections_.resize(requests_.size());
    project_to_surface(*evaluator_, requests_, projections_, settings_.projection);
    for (std::size_t i = 0; i < pending_.size(); ++i) {
        Triangle& T = triangles_[pending_[i]];
        const Projection& p = projections_[i];
        T.candidate = p.position;
        T.candidate_normal = p.on_surface() ? p.normal : unit_or_zero(requests_[i].direction);
        T.candidate_gradient_norm = p.gradient_norm;
        T.candidate_on_surface = p.on_surface();
        T.candidate_refused = !p.on_surface() || !settings_.box.contains(p.position);
        T.candidate_retried = false;
        T.candidate_version = version_;
    }
}

TriangleGeometry Refiner::Impl::geometry(std::uint32_t t) const {
    const Triangle& T = triangles_[t];
    double gradient_norm = 0.0;  // the mean over the corners, or 0 if one is unknown
    for (std::uint32_t v : T.v) {
        const double g = vertices_[v].gradient_norm;
        gradient_norm = g > 0.0 && gradient_norm >= 0.0 ? gradient_norm + g / 3.0 : -1.0;
    }
    const glm::dvec3 midpoint = T.state == TriangleState::Split
                                    ? vertices_[records_[T.split].vertex].position
                                    : T.candidate;
    return {position(t, T.base), position(t, T.base + 1), position(t, T.base + 2), midpoint,
            std::max(gradient_norm, 0.0)};
}

void Refiner::Impl::ensure_errors(std::span<const std::uint32_t> tris) {
    stale_.clear();
    for (std::uint32_t t : tris)
        if (triangles_[t].error_version != version_) stale_.push_back(t);
    if (stale_.empty()) return;
    // The base midpoint is projected here only for measures that read it; otherwise only when
    // the triangle is split.
    if (settings_.error_measure->needs_projected_midpoint()) {
        std::vector<std::uint32_t> leaves;
        for (std::uint32_t t : stale_)
            if (triangles_[t].state != TriangleState::Split) leaves.push_back(t);
        ensure_candidates(leaves);
    }
    geometries_.clear();
    for (std::uint32_t t : stale_) geometries_.push_back(geometry(t));
    errors_.resize(stale_.size());
    settings_.error_measure->triangle_errors(*evaluator_, geometries_, errors_);
    for (std::size_t i = 0; i < stale_.size(); ++i) {
        Triangle& T = triangles_[stale_[i]];
        T.error = errors_[i] >= 0.0 ? errors_[i] : 0.0;  // NaN or negative from a custom measure
        T.error_version = version_;
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
    delta_.add_triangle(delta_triangle(t));
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
