#include "refine/mesh_delta.h"

#include <algorithm>
#include <array>
#include <cassert>

namespace isomesh {
namespace {

std::string describe(const char* what, std::uint32_t id) {
    return std::string(what) + " " + std::to_string(id);
}

}  // namespace

MeshDelta DeltaBuilder::take() {
    // Ids and data overloaded by entry type: the two logs' entries differ.
    struct Id {
        std::uint32_t operator()(const VertexChange& c) const { return c.vertex.id; }
        std::uint32_t operator()(const TriangleChange& c) const { return c.triangle.id; }
    };
    MeshDelta delta = net_delta(
        vertices_, triangles_, runs_, Id{}, [](const VertexChange& c) { return c.vertex; },
        [](const TriangleChange& c) { return c.triangle; });
    vertices_.clear();
    triangles_.clear();
    return delta;
}

std::string DeltaMesh::apply(const MeshDelta& delta) {
    for (std::uint32_t id : delta.removed_triangles) {
        auto it = triangles_.find(id);
        if (it == triangles_.end()) return describe("removing unknown triangle", id);
        for (std::uint32_t v : it->second.vertices) --uses_[v];
        triangles_.erase(it);
    }
    for (std::uint32_t id : delta.removed_vertices) {
        if (!vertices_.contains(id)) return describe("removing unknown vertex", id);
        if (uses_[id] != 0) return describe("removing a vertex still in use:", id);
        vertices_.erase(id);
        uses_.erase(id);
    }
    for (const DeltaVertex& v : delta.added_vertices)
        if (!vertices_.emplace(v.id, v).second) return describe("adding known vertex", v.id);
    for (const DeltaVertex& v : delta.moved_vertices) {
        auto it = vertices_.find(v.id);
        if (it == vertices_.end()) return describe("moving unknown vertex", v.id);
        it->second = v;
    }
    for (const DeltaTriangle& t : delta.added_triangles) {
        for (std::uint32_t v : t.vertices)
            if (!vertices_.contains(v)) return describe("triangle uses unknown vertex", v);
        if (!triangles_.emplace(t.id, t).second) return describe("adding known triangle", t.id);
        for (std::uint32_t v : t.vertices) ++uses_[v];
    }
    return {};
}

std::vector<std::uint32_t> DeltaMesh::triangle_ids() const {
    std::vector<std::uint32_t> ids;
    ids.reserve(triangles_.size());
    for (const auto& entry : triangles_) ids.push_back(entry.first);
    std::sort(ids.begin(), ids.end());
    return ids;
}

Mesh DeltaMesh::to_mesh() const {
    std::vector<std::uint32_t> vertex_ids;
    vertex_ids.reserve(vertices_.size());
    for (const auto& entry : vertices_) vertex_ids.push_back(entry.first);
    std::sort(vertex_ids.begin(), vertex_ids.end());
    std::unordered_map<std::uint32_t, std::uint32_t> index;
    Mesh mesh;
    for (std::uint32_t id : vertex_ids) {
        index[id] = static_cast<std::uint32_t>(mesh.positions.size());
        mesh.positions.push_back(vertices_.at(id).position);
        mesh.normals.push_back(vertices_.at(id).normal);
    }
    for (std::uint32_t id : triangle_ids()) {
        const auto& v = triangles_.at(id).vertices;
        mesh.triangles.push_back({index.at(v[0]), index.at(v[1]), index.at(v[2])});
    }
    return mesh;
}

}  // namespace isomesh
