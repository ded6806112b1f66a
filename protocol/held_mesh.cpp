// The mesh a client holds (see held_mesh.h).
#include "protocol/held_mesh.h"

#include <algorithm>

namespace isomesh::protocol {

const HeldMesh::Corners* HeldMesh::triangle(std::uint64_t id) const {
    auto it = triangles_.find(id);
    return it == triangles_.end() ? nullptr : &it->second;
}

const Vertex* HeldMesh::vertex(std::uint32_t id) const {
    auto it = vertices_.find(id);
    return it == vertices_.end() ? nullptr : &it->second;
}

std::span<const std::uint64_t> HeldMesh::star(std::uint32_t id) const {
    auto it = stars_.find(id);
    if (it == stars_.end()) return {};
    return it->second;
}

void HeldMesh::clear() {
    triangles_.clear();
    vertices_.clear();
    stars_.clear();
}

void HeldMesh::remove(std::uint64_t id) {
    auto it = triangles_.find(id);
    if (it == triangles_.end()) return;
    for (std::uint32_t v : it->second) {
        auto star = stars_.find(v);
        std::erase(star->second, id);
        if (star->second.empty()) {
            stars_.erase(star);
            vertices_.erase(v);
        }
    }
    triangles_.erase(it);
}

void HeldMesh::add(std::uint64_t id, const Corners& corners) {
    triangles_.emplace(id, corners);
    for (std::uint32_t v : corners) stars_[v].push_back(id);
}

void HeldMesh::apply(const DecodedFrame& frame) {
    if (frame.header.kind == FrameKind::keyframe) clear();
    for (std::uint64_t id : frame.removed) remove(id);
    for (const Vertex& v : frame.vertices) vertices_[v.id] = v;
    for (const FrameTriangle& t : frame.triangles) add(t.id, t.vertices);
    // A vertex sent without a triangle (a moved vertex whose triangles were all removed) is not
    // kept: nothing uses it.
    for (const Vertex& v : frame.vertices) {
        if (!stars_.contains(v.id)) vertices_.erase(v.id);
    }
}

}  // namespace isomesh::protocol
