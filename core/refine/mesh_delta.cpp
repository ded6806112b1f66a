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

template <typename Entry>
void DeltaBuilder::index_by_id(const HugePageVector<Entry>& log,
                               std::uint32_t (*id_of)(const Entry&)) {
    // For every id in the log, in increasing id order, the log indices of its first and last
    // change (visit_runs): what a stable sort by id followed by a scan of each run of equal ids
    // gives, without the sort where the ids are compact (they are: ids are given in sequence,
    // and a step changes mostly recent ones): by_id_[id - lo] holds the id's run.
    by_id_.clear();
    keys_.clear();
    if (log.empty()) return;
    std::uint32_t lo = id_of(log[0]), hi = lo;
    for (const Entry& c : log) {
        lo = std::min(lo, id_of(c));
        hi = std::max(hi, id_of(c));
    }
    const std::size_t range = std::size_t{hi} - lo + 1;
    if (range <= 4 * log.size() + 1024) {
        by_id_.assign(range, Run{kNoChange, kNoChange});
        for (std::uint32_t i = 0; i < log.size(); ++i) {
            Run& run = by_id_[id_of(log[i]) - lo];
            if (run[0] == kNoChange) run[0] = i;
            run[1] = i;
        }
        return;
    }
    // Sparse ids: sort (id, index) keys; they are unique, so the order is the stable one.
    for (std::uint32_t i = 0; i < log.size(); ++i)
        keys_.push_back(std::uint64_t{id_of(log[i])} << 32 | i);
    std::sort(keys_.begin(), keys_.end());
}

template <typename Visit>
void DeltaBuilder::visit_runs(Visit visit) const {
    for (const Run& run : by_id_)
        if (run[0] != kNoChange) visit(run);
    for (std::size_t i = 0; i < keys_.size();) {
        std::size_t j = i + 1;
        while (j < keys_.size() && keys_[j] >> 32 == keys_[i] >> 32) ++j;
        visit(Run{static_cast<std::uint32_t>(keys_[i]), static_cast<std::uint32_t>(keys_[j - 1])});
        i = j;
    }
}

MeshDelta DeltaBuilder::take() {
    MeshDelta delta;
    // Net vertex changes: added (then maybe moved) -> added at its last place, unless removed;
    // moved -> moved to its last place, unless removed; removed -> removed.
    enum VertexList { kRemovedVertex, kAddedVertex, kMovedVertex };
    index_by_id(
        vertices_, +[](const VertexChange& c) { return c.vertex.id; });
    const auto vertex_list = [&](const Run& run) {
        const VertexChange& first = vertices_[run[0]];
        if (vertices_[run[1]].change == Change::Removed)
            return first.change != Change::Added ? int(kRemovedVertex) : 3;
        return first.change == Change::Added ? int(kAddedVertex) : int(kMovedVertex);
    };
    std::array<std::size_t, 4> counts{};
    visit_runs([&](const Run& run) { ++counts[vertex_list(run)]; });
    delta.removed_vertices.reserve(counts[kRemovedVertex]);
    delta.added_vertices.reserve(counts[kAddedVertex]);
    delta.moved_vertices.reserve(counts[kMovedVertex]);
    visit_runs([&](const Run& run) {
        switch (vertex_list(run)) {
            case kRemovedVertex:
                delta.removed_vertices.push_back(vertices_[run[0]].vertex.id);
                break;
            case kAddedVertex:
                delta.added_vertices.push_back(vertices_[run[1]].vertex);
                break;
            case kMovedVertex:
                delta.moved_vertices.push_back(vertices_[run[1]].vertex);
                break;
            default:
                break;
        }
    });
    // Net triangle changes: an id always names the same vertices, so only the first and the last
    // change matter (add..add: added; remove..remove: removed; otherwise no change).
    index_by_id(
        triangles_, +[](const TriangleChange& c) { return c.triangle.id; });
    counts = {};
    visit_runs([&](const Run& run) {
        if (triangles_[run[0]].change == triangles_[run[1]].change)
            ++counts[triangles_[run[0]].change == Change::Added ? 0 : 1];
    });
    delta.added_triangles.reserve(counts[0]);
    delta.removed_triangles.reserve(counts[1]);
    visit_runs([&](const Run& run) {
        const TriangleChange& first = triangles_[run[0]];
        if (first.change != triangles_[run[1]].change) return;
        if (first.change == Change::Added)
            delta.added_triangles.push_back(first.triangle);
        else
            delta.removed_triangles.push_back(first.triangle.id);
    });
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
