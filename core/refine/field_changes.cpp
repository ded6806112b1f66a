// Function versions (the thesis, 3.2.3 "Dynamic data"): a new function bumps the version; every
// vertex moves onto the new surface, then leaves and mergeable splits are re-evaluated, in batches
// and coarse before fine; elements out of sight (split triangles) are updated only when they come
// back. A change of topology is for the refiner's owner to see (it compares a fresh phase-1 mesh
// with root_topology()); it then starts again from that mesh with reset().
#include <algorithm>
#include <cassert>
#include <stdexcept>

#include "mesh/topology.h"
#include "refine/refiner_impl.h"

namespace isomesh {

using namespace refiner_detail;

// ---------------------------------------------------------------------------------------------
// Function versions

void Refiner::Impl::set_field(std::shared_ptr<const Field> field) {
    if (!field) throw std::invalid_argument("Refiner::set_field: null field");
    field_ = std::move(field);
    evaluator_ = field_->make_evaluator();
    ++version_;
    refresh_failed_ = false;
    // The most outdated vertices first (when the function changes faster than the refresh
    // completes, no vertex is left behind), then in id order: coarse before fine.
    refresh_list_.clear();
    for (std::uint32_t v = 0; v < vertices_.size(); ++v)
        if (vertices_[v].alive) refresh_list_.push_back(v);
    std::sort(refresh_list_.begin(), refresh_list_.end(), [&](std::uint32_t a, std::uint32_t b) {
        const Vertex &va = vertices_[a], &vb = vertices_[b];
        return va.version != vb.version ? va.version < vb.version : va.id < vb.id;
    });
    refresh_next_ = 0;
    refresh_stage_ = RefreshStage::Vertices;
}

bool Refiner::Impl::refresh_pending() const {
    return refresh_stage_ != RefreshStage::None;
}

void Refiner::Impl::skip_finished_refresh_stages() {
    while (refresh_stage_ != RefreshStage::None && refresh_next_ == refresh_list_.size()) {
        refresh_list_.clear();
        refresh_next_ = 0;
        if (refresh_stage_ == RefreshStage::Vertices) {
            refresh_stage_ = RefreshStage::Leaves;
            for (std::uint32_t t = 0; t < triangles_.size(); ++t)
                if (triangles_[t].state == TriangleState::Leaf) refresh_list_.push_back(t);
        } else if (refresh_stage_ == RefreshStage::Leaves) {
            refresh_stage_ = RefreshStage::Records;
            for (std::uint32_t r = 0; r < records_.size(); ++r)
                if (merge_queue_->contains(r)) refresh_list_.push_back(r);
        } else {
            refresh_stage_ = RefreshStage::None;
        }
    }
}

std::size_t Refiner::Impl::refresh_some(std::size_t limit) {
    skip_finished_refresh_stages();
    if (refresh_stage_ == RefreshStage::None) return 0;
    // Items are refreshed in batches (batched evaluations); each item's result does not depend
    // on the batch it is in, so neither does the mesh depend on the step sizes.
    constexpr std::size_t kBatch = 256;
    const std::size_t count = std::min({limit, kBatch, refresh_list_.size() - refresh_next_});
    const std::span<const std::uint32_t> items(refresh_list_.data() + refresh_next_, count);
    refresh_next_ += count;
    if (refresh_stage_ == RefreshStage::Vertices)
        refresh_vertices(items);
    else if (refresh_stage_ == RefreshStage::Leaves)
        refresh_leaves(items);
    else
        refresh_records(items);
    // The last batch ends the refresh at once: field_change_pending() is false right after it.
    skip_finished_refresh_stages();
    return count;
}

void Refiner::Impl::refresh_vertices(std::span<const std::uint32_t> items) {
    requests_.clear();
    for (std::uint32_t v : items) {
        const Vertex& V = vertices_[v];
        ProjectionRequest request;
        request.start = V.position;
        request.direction = V.normal;
        request.slope = V.gradient_norm;
        // The phase-1 edge length bounds how far a vertex may travel: beyond it the phase-1
        // topology guarantee says nothing, and the fresh phase-1 mesh takes over.
        request.scale = 2.0 * std::max(root_edge_length_, V.scale);
        request.fixed_axes = V.fixed_axes;
        requests_.push_back(request);
    }
    projections_.resize(requests_.size());
    project_to_surface(*evaluator_, requests_, projections_, settings_.projection);
    for (std::size_t i = 0; i < items.size(); ++i) {
        Vertex& V = vertices_[items[i]];
        const Projection& p = projections_[i];
        if (p.on_surface()) {
            V.position = p.position;
            V.normal = p.normal;
            V.gradient_norm = p.gradient_norm;
        } else {
            ++counters_.failed_refreshes;
            refresh_failed_ = true;
        }
        V.on_surface = p.on_surface();
        V.version = version_;
        delta_.move_vertex(V.id, items[i]);
    }
    counters_.refreshed_vertices += items.size();
}

void Refiner::Impl::refresh_leaves(std::span<const std::uint32_t> items) {
    std::vector<double> old_errors;
    old_errors.reserve(items.size());
    for (std::uint32_t t : items) old_errors.push_back(triangles_[t].error);
    ensure_errors(items);
    for (std::size_t i = 0; i < items.size(); ++i) {
        const std::uint32_t t = items[i];
        const double error = triangles_[t].error;
        total_error_.add(error - old_errors[i]);
        // A split refused for the old function (no vertex for it) may be possible now.
        if (split_queue_->contains(t)) split_queue_->remove(t);
        if (blocked_queue_->contains(t)) blocked_queue_->remove(t);
        (splittable(t) ? *split_queue_ : *blocked_queue_).insert(t, error);
    }
    counters_.refreshed_triangles += items.size();
}

void Refiner::Impl::refresh_records(std::span<const std::uint32_t> items) {
    std::vector<std::uint32_t> parents;
    for (std::uint32_t r : items)
        for (std::uint32_t p : records_[r].parents)
            if (p != kNone) parents.push_back(p);
    ensure_errors(parents);
    for (std::uint32_t r : items) merge_queue_->update(r, merge_priority(r));
}

void Refiner::Impl::reset(const Mesh& first_mesh) {
    if (const std::string problem = validate_refinable(first_mesh); !problem.empty())
        throw std::invalid_argument("Refiner::reset: " + problem);
    clear_all_into_delta();
    refresh_stage_ = RefreshStage::None;
    refresh_list_.clear();
    refresh_next_ = 0;
    refresh_failed_ = false;
    load(first_mesh);
    restarted_ = true;
    ++counters_.restarts;
}

std::size_t Refiner::Impl::inverted_triangles() const {
    std::size_t inverted = 0;
    for (std::uint32_t t = 0; t < triangles_.size(); ++t) {
        const Triangle& T = triangles_[t];
        if (T.state != TriangleState::Leaf) continue;
        const glm::dvec3 normal =
            glm::cross(position(t, 1) - position(t, 0), position(t, 2) - position(t, 0));
        const glm::dvec3 surface =
            vertices_[T.v[0]].normal + vertices_[T.v[1]].normal + vertices_[T.v[2]].normal;
        if (glm::dot(normal, surface) < 0.0) ++inverted;
    }
    return inverted;
}

}  // namespace isomesh
