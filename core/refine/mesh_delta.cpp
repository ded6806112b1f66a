#include "refine/mesh_delta.h"

#include <algorithm>
#include <cassert>

namespace isomesh {
namespace {

std::string describe(const char* what, std::uint32_t id) {
    return std::string(what) + " " + std::to_string(id);
}

}  // namespace

MeshDelta DeltaBuilder::take() {
    MeshDelta delta;
    // Net vertex changes: added (then maybe moved) -> added at its last place, unless removed;
    // moved -> moved to its last place, unless removed; removed -> removed.
    std::stable_sort(
        vertices_.begin(), vertices_.end(),
        [](const VertexChange& a, const VertexChange& b) { return a.vertex.id < b.vertex.id; });
    for (std::size_t i = 0; i < vertices_.size();) {
        std::size_t j = i;
        while (j < vertices_.size() && vertices_[j].vertex.id == vertices_[i].vertex.id) ++j;
        const VertexChange& first = vertices_[i];
        const VertexChange& last = vertices_[j - 1];
        assert(std::count_if(vertices_.begin() + i, vertices_.begin() + j, [](const auto& c) {
                   return c.change == Change::Added;
               }) <= (first.change == Change::Added ? 1 : 0));
        if (last.change == Change::Removed) {
            if (first.change != Change::Added) delta.removed_vertices.push_back(first.vertex.id);
        } else if (first.change == Change::Added) {
            delta.added_vertices.push_back(last.vertex);
        } else {
            delta.moved_vertices.push_back(last.vertex);
        }
        i = j;
    }
    // Net triangle changes: an id always names the same vertices, so only the first and the last
    // change matter (add..add: added; remove..remove: removed; otherwise no change).
    std::stable_sort(triangles_.begin(), triangles_.end(),
                     [](const TriangleChange& a, const TriangleChange& b) {
                         return a.triangle.id < b.triangle.id;
                     });
    for (std::size_t i = 0; i < triangles_.size();) {
        std::size_t j = i;
        while (j < triangles_.size() && triangles_[j].triangle.id == triangles_[i].triangle.id) ++j;
        const TriangleChange& first = triangles_[i];
        const TriangleChange& last = triangles_[j - 1];
        if (first.change == last.change) {
            if (first.change == Change::Added)
                delta.added_triangles.push_back(first.triangle);
            else
                delta.removed_triangles.push_back(first.triangle.id);
        }
        i = j;
    }
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
