#include "refine/mesh_delta.h"

#include <algorithm>
#include <cassert>

namespace isomesh {
namespace {

template <typename T, typename Key>
void sort_by(std::vector<T>& items, Key key) {
    std::sort(items.begin(), items.end(), [&](const T& a, const T& b) { return key(a) < key(b); });
}

std::string describe(const char* what, std::uint32_t id) {
    return std::string(what) + " " + std::to_string(id);
}

}  // namespace

void DeltaBuilder::add_vertex(const DeltaVertex& vertex) {
    assert(!vertices_.contains(vertex.id) && "vertex ids are never reused");
    vertices_[vertex.id] = {Change::Added, vertex};
}

void DeltaBuilder::move_vertex(const DeltaVertex& vertex) {
    auto [it, inserted] = vertices_.try_emplace(vertex.id, VertexChange{Change::Moved, vertex});
    if (inserted) return;
    assert(it->second.change != Change::Removed && "moving a removed vertex");
    it->second.vertex = vertex;  // an added vertex stays added, at its new place
}

void DeltaBuilder::remove_vertex(std::uint32_t id) {
    auto it = vertices_.find(id);
    if (it != vertices_.end() && it->second.change == Change::Added) {
        vertices_.erase(it);  // created and removed within this delta
        return;
    }
    vertices_[id] = {Change::Removed, DeltaVertex{id, {}, {}}};
}

void DeltaBuilder::add_triangle(const DeltaTriangle& triangle) {
    auto it = triangles_.find(triangle.id);
    if (it != triangles_.end()) {
        assert(it->second.change == Change::Removed);
        triangles_.erase(it);  // removed and restored (same id, same vertices): no change
        return;
    }
    triangles_[triangle.id] = {Change::Added, triangle};
}

void DeltaBuilder::remove_triangle(std::uint32_t id) {
    auto it = triangles_.find(id);
    if (it != triangles_.end()) {
        assert(it->second.change == Change::Added);
        triangles_.erase(it);  // created and removed within this delta
        return;
    }
    triangles_[id] = {Change::Removed, DeltaTriangle{id, {}}};
}

MeshDelta DeltaBuilder::take() {
    MeshDelta delta;
    for (const auto& [id, c] : vertices_) {
        if (c.change == Change::Added) delta.added_vertices.push_back(c.vertex);
        if (c.change == Change::Moved) delta.moved_vertices.push_back(c.vertex);
        if (c.change == Change::Removed) delta.removed_vertices.push_back(id);
    }
    for (const auto& [id, c] : triangles_) {
        if (c.change == Change::Added) delta.added_triangles.push_back(c.triangle);
        if (c.change == Change::Removed) delta.removed_triangles.push_back(id);
    }
    auto id_of = [](const auto& item) { return item.id; };
    auto self = [](std::uint32_t id) { return id; };
    sort_by(delta.added_vertices, id_of);
    sort_by(delta.moved_vertices, id_of);
    sort_by(delta.added_triangles, id_of);
    sort_by(delta.removed_vertices, self);
    sort_by(delta.removed_triangles, self);
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
