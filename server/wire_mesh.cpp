#include "server/wire_mesh.h"

#include <algorithm>
#include <cassert>

#include <absl/container/flat_hash_set.h>

namespace isomesh::server {
namespace {

protocol::Vertex wire_vertex(std::uint32_t id, const glm::dvec3& position,
                             const glm::dvec3& normal) {
    return {id, glm::vec3(position), glm::vec3(normal)};
}

}  // namespace

void WireMesh::reset(const Mesh& mesh, std::span<const std::uint32_t> triangle_ids,
                     std::span<const std::uint32_t> vertex_ids) {
    assert(triangle_ids.size() == mesh.triangle_count());
    assert(vertex_ids.size() == mesh.vertex_count());
    triangles_.clear();
    vertices_.clear();
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
        const glm::dvec3 normal = v < mesh.normals.size() ? mesh.normals[v] : glm::dvec3(0.0);
        vertices_[vertex_ids[v]] = wire_vertex(vertex_ids[v], mesh.positions[v], normal);
    }
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
        const auto& corners = mesh.triangles[t];
        triangles_[triangle_ids[t]] = {
            {vertex_ids[corners[0]], vertex_ids[corners[1]], vertex_ids[corners[2]]},
            next_wire_id_++};
    }
}

WireDelta WireMesh::apply(const MeshDelta& delta) {
    WireDelta content;
    for (std::uint32_t id : delta.removed_triangles) {
        auto it = triangles_.find(id);
        assert(it != triangles_.end());
        content.removed.push_back(it->second.wire_id);
        triangles_.erase(it);
    }
    for (std::uint32_t id : delta.removed_vertices) vertices_.erase(id);
    for (const DeltaVertex& v : delta.added_vertices)
        vertices_[v.id] = wire_vertex(v.id, v.position, v.normal);

    auto add = [&](std::uint32_t id, const std::array<std::uint32_t, 3>& corners) {
        content.triangles.push_back({corners});
        content.refiner_ids.push_back(id);
    };
    for (const DeltaTriangle& t : delta.added_triangles) {
        triangles_[t.id] = {t.vertices, kUnassigned};
        add(t.id, t.vertices);
    }
    if (!delta.moved_vertices.empty()) {
        absl::flat_hash_set<std::uint32_t> moved;
        for (const DeltaVertex& v : delta.moved_vertices) {
            vertices_[v.id] = wire_vertex(v.id, v.position, v.normal);
            moved.insert(v.id);
        }
        std::vector<std::uint32_t> resent;  // live triangles around a moved vertex, sent before
        for (auto& [id, triangle] : triangles_) {
            const auto& c = triangle.vertices;
            if (triangle.wire_id == kUnassigned) continue;  // added by this delta
            if (moved.contains(c[0]) || moved.contains(c[1]) || moved.contains(c[2])) {
                content.removed.push_back(triangle.wire_id);
                triangle.wire_id = kUnassigned;
                resent.push_back(id);
            }
        }
        std::sort(resent.begin(), resent.end());
        for (std::uint32_t id : resent) add(id, triangles_.at(id).vertices);
    }
    std::sort(content.removed.begin(), content.removed.end());

    absl::flat_hash_set<std::uint32_t> used;
    for (const protocol::Triangle& t : content.triangles) {
        for (std::uint32_t v : t.vertices) {
            if (used.insert(v).second) content.vertices.push_back(vertices_.at(v));
        }
    }
    return content;
}

bool WireMesh::follow(const MeshDelta& delta) {
    bool changed = !delta.removed_triangles.empty() || !delta.added_triangles.empty();
    for (std::uint32_t id : delta.removed_triangles) triangles_.erase(id);
    for (std::uint32_t id : delta.removed_vertices) vertices_.erase(id);
    for (const DeltaVertex& v : delta.added_vertices)
        vertices_[v.id] = wire_vertex(v.id, v.position, v.normal);
    for (const DeltaTriangle& t : delta.added_triangles)
        triangles_[t.id] = {t.vertices, next_wire_id_++};
    for (const DeltaVertex& v : delta.moved_vertices) {
        auto it = vertices_.find(v.id);
        if (it == vertices_.end()) continue;  // moved, then dropped
        it->second = wire_vertex(v.id, v.position, v.normal);
        changed = true;
    }
    return changed;
}

void WireMesh::commit_wire_ids(std::span<const std::uint32_t> refiner_ids,
                               std::span<const std::uint64_t> wire_ids) {
    assert(refiner_ids.size() == wire_ids.size());
    for (std::size_t i = 0; i < refiner_ids.size(); ++i) {
        triangles_.at(refiner_ids[i]).wire_id = wire_ids[i];
        next_wire_id_ = std::max(next_wire_id_, wire_ids[i] + 1);
    }
}

KeyframeContent WireMesh::keyframe() const {
    std::vector<std::pair<std::uint64_t, const LiveTriangle*>> order;
    order.reserve(triangles_.size());
    for (const auto& [id, triangle] : triangles_) order.emplace_back(triangle.wire_id, &triangle);
    std::sort(order.begin(), order.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });

    KeyframeContent content;
    absl::flat_hash_set<std::uint32_t> used;
    for (const auto& [wire_id, triangle] : order) {
        assert(wire_id != kUnassigned);
        content.triangles.push_back({triangle->vertices});
        content.wire_ids.push_back(wire_id);
        for (std::uint32_t v : triangle->vertices) {
            if (used.insert(v).second) content.vertices.push_back(vertices_.at(v));
        }
    }
    return content;
}

}  // namespace isomesh::server

namespace isomesh::server {

RefinerMesh WireMesh::refiner_mesh() const {
    RefinerMesh out;
    out.vertices.reserve(vertices_.size());
    for (const auto& [id, vertex] : vertices_) out.vertices.push_back(vertex);
    std::sort(out.vertices.begin(), out.vertices.end(),
              [](const protocol::Vertex& a, const protocol::Vertex& b) { return a.id < b.id; });
    out.triangles.reserve(triangles_.size());
    for (const auto& [id, triangle] : triangles_)
        out.triangles.push_back({id, {triangle.vertices}});
    std::sort(out.triangles.begin(), out.triangles.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    return out;
}

}  // namespace isomesh::server
