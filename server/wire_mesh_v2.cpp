#include "server/wire_mesh_v2.h"

#include <algorithm>

#include <absl/container/flat_hash_set.h>

#include "protocol/delta_v2_geometry.h"

namespace isomesh::server {
namespace {

/// The vertex as a client decodes it from any version-2 frame on `grid`.
protocol::Vertex as_decoded(std::uint32_t id, const protocol::Vertex& v,
                            const protocol::GridMath& grid) {
    return {id, grid.dequantize(grid.quantize(v.position)),
            grid.decode_normal(grid.encode_normal(glm::dvec3(v.normal)))};
}

}  // namespace

void WireMeshV2::reset(const RefinerMesh& mesh, const protocol::QuantizationGrid& grid) {
    grid_ = grid;
    const protocol::GridMath math(grid);
    held_.clear();
    triangle_of_.clear();
    refiner_of_.clear();
    vertex_of_.clear();
    vertex_of_.reserve(mesh.vertices.size());
    Staged staged;
    staged.content.header.kind = protocol::FrameKind::keyframe;
    staged.content.vertices.reserve(mesh.vertices.size());
    for (const protocol::Vertex& v : mesh.vertices) {
        vertex_of_[v.id] = next_vertex_;
        staged.content.vertices.push_back(as_decoded(next_vertex_++, v, math));
    }
    staged.first_id = next_triangle_;
    staged.content.triangles.reserve(mesh.triangles.size());
    staged.refiners.reserve(mesh.triangles.size());
    for (const auto& [refiner_id, t] : mesh.triangles) {
        const auto& c = t.vertices;
        staged.content.triangles.push_back(
            {next_triangle_++, {vertex_of_.at(c[0]), vertex_of_.at(c[1]), vertex_of_.at(c[2])}});
        staged.refiners.push_back(refiner_id);
    }
    staged_ = std::move(staged);
    valid_ = true;
    renumberable_ = true;
}

void WireMeshV2::commit() {
    if (!staged_) return;
    const std::vector<protocol::FrameTriangle>& triangles = staged_->content.triangles;
    triangle_of_.reserve(triangles.size());
    refiner_of_.reserve(triangles.size());
    for (std::size_t i = 0; i < triangles.size(); ++i) {
        triangle_of_[staged_->refiners[i]] = triangles[i].id;
        refiner_of_[triangles[i].id] = staged_->refiners[i];
    }
    held_.apply(staged_->content);
    staged_.reset();
}

void WireMeshV2::renumber(std::span<const std::uint64_t> from, std::span<const std::uint64_t> to) {
    if (staged_) {
        // Not built yet: the staged triangles take their final ids, then go in once.
        auto& triangles = staged_->content.triangles;
        for (std::size_t i = 0; i < from.size(); ++i) {
            triangles[from[i] - staged_->first_id].id = to[i];
            next_triangle_ = std::max(next_triangle_, to[i] + 1);
        }
        commit();
        renumberable_ = false;
        return;
    }
    protocol::DecodedFrame content;
    content.header.kind = protocol::FrameKind::keyframe;
    for (const auto& [id, v] : held_.vertices()) content.vertices.push_back(v);
    protocol::IdTable<std::uint32_t, std::uint64_t> triangle_of;
    protocol::IdTable<std::uint64_t, std::uint32_t> refiner_of;
    for (std::size_t i = 0; i < from.size(); ++i) {
        content.triangles.push_back({to[i], *held_.triangle(from[i])});
        const std::uint32_t refiner = refiner_of_.at(from[i]);
        triangle_of[refiner] = to[i];
        refiner_of[to[i]] = refiner;
        next_triangle_ = std::max(next_triangle_, to[i] + 1);
    }
    held_.apply(content);
    triangle_of_ = std::move(triangle_of);
    refiner_of_ = std::move(refiner_of);
    renumberable_ = false;
}

protocol::Result<protocol::EncodedDeltaV2> WireMeshV2::encode(const protocol::FrameInfo& info,
                                                              const MeshDelta& delta) {
    commit();
    protocol::DeltaV2Change change;
    for (std::uint32_t id : delta.removed_triangles) {
        const auto it = triangle_of_.find(id);
        change.removed.push_back(it->second);
        refiner_of_.erase(it->second);
        triangle_of_.erase(it);
    }
    protocol::IdTable<std::uint32_t, std::uint32_t> provisional;
    for (const DeltaVertex& v : delta.added_vertices) {
        const auto id = static_cast<std::uint32_t>(next_vertex_ + change.new_vertices.size());
        provisional[v.id] = id;
        change.new_vertices.push_back({id, glm::vec3(v.position), glm::vec3(v.normal)});
    }
    for (const DeltaVertex& v : delta.moved_vertices) {
        change.moved_vertices.push_back(
            {vertex_of_.at(v.id), glm::vec3(v.position), glm::vec3(v.normal)});
    }
    auto wire_vertex = [&](std::uint32_t id) {
        auto it = provisional.find(id);
        return it != provisional.end() ? it->second : vertex_of_.at(id);
    };
    for (const DeltaTriangle& t : delta.added_triangles) {
        const auto& c = t.vertices;
        change.added.push_back({{wire_vertex(c[0]), wire_vertex(c[1]), wire_vertex(c[2])}});
    }
    auto encoded =
        protocol::encode_delta_v2(info, held_, change, next_triangle_, next_vertex_, grid_);
    if (!encoded) return encoded;
    renumberable_ = false;
    const protocol::EncodedDeltaV2& e = encoded.value();
    for (std::uint32_t id : delta.removed_vertices) vertex_of_.erase(id);
    for (std::size_t i = 0; i < delta.added_vertices.size(); ++i)
        vertex_of_[delta.added_vertices[i].id] = e.vertex_ids[i];
    for (std::size_t i = 0; i < delta.added_triangles.size(); ++i) {
        triangle_of_[delta.added_triangles[i].id] = e.triangle_ids[i];
        refiner_of_[e.triangle_ids[i]] = delta.added_triangles[i].id;
    }
    for (const auto& [old_id, new_id] : e.renamed) {
        const std::uint32_t refiner = refiner_of_.at(old_id);
        refiner_of_.erase(old_id);
        refiner_of_[new_id] = refiner;
        triangle_of_[refiner] = new_id;
    }
    held_.apply(e.applied);
    next_triangle_ = e.next_triangle_id;
    next_vertex_ = e.next_vertex_id;
    return encoded;
}

KeyframeContent WireMeshV2::keyframe() const {
    KeyframeContent content;
    if (staged_) {
        // In id order already; every vertex once (those no triangle uses are ignored).
        content.vertices = staged_->content.vertices;
        for (const protocol::FrameTriangle& t : staged_->content.triangles) {
            content.wire_ids.push_back(t.id);
            content.triangles.push_back({t.vertices});
        }
        return content;
    }
    for (const auto& [id, c] : held_.triangles()) content.wire_ids.push_back(id);
    std::sort(content.wire_ids.begin(), content.wire_ids.end());
    absl::flat_hash_set<std::uint32_t> listed;
    for (std::uint64_t id : content.wire_ids) {
        const auto& c = *held_.triangle(id);
        content.triangles.push_back({c});
        for (std::uint32_t v : c) {
            if (listed.insert(v).second) content.vertices.push_back(*held_.vertex(v));
        }
    }
    return content;
}

}  // namespace isomesh::server
