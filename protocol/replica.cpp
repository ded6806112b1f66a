// Applying frames to a client-side mesh (see replica.h). Vertices are reference-counted by the
// triangles that use them and dropped when unused: every payload carries all vertices its
// triangles use, so a dropped vertex is never needed again without being re-sent.
#include "protocol/replica.h"

#include <algorithm>

namespace isomesh::protocol {

MeshReplica::Outcome MeshReplica::apply(const DecodedFrame& frame) {
    const FrameHeader& h = frame.header;
    if (h.kind == FrameKind::keyframe) {
        reset();
        add_triangles(frame);
        synchronized_ = true;
        sequence_ = h.sequence;
        function_version_ = h.function_version;
        return Outcome::applied;
    }
    if (!synchronized_) return Outcome::awaiting_keyframe;
    if (h.sequence <= sequence_) return Outcome::stale;
    if (h.sequence != sequence_ + 1) {
        synchronized_ = false;
        return Outcome::gap;
    }
    if (!apply_delta(frame)) {
        synchronized_ = false;
        return Outcome::inconsistent;
    }
    sequence_ = h.sequence;
    function_version_ = h.function_version;
    return Outcome::applied;
}

std::vector<FrameTriangle> MeshReplica::sorted_triangles() const {
    std::vector<FrameTriangle> out;
    out.reserve(triangles_.size());
    for (const auto& [id, vertices] : triangles_) out.push_back({id, canonical_rotation(vertices)});
    std::sort(out.begin(), out.end(),
              [](const FrameTriangle& a, const FrameTriangle& b) { return a.id < b.id; });
    return out;
}

void MeshReplica::reset() {
    triangles_.clear();
    vertices_.clear();
    uses_.clear();
}

bool MeshReplica::apply_delta(const DecodedFrame& frame) {
    for (std::uint64_t id : frame.removed) {
        auto it = triangles_.find(id);
        if (it == triangles_.end()) return false;
        for (std::uint32_t v : it->second) {
            if (--uses_[v] == 0) {
                uses_.erase(v);
                vertices_.erase(v);
            }
        }
        triangles_.erase(it);
    }
    for (const FrameTriangle& t : frame.triangles) {
        if (triangles_.contains(t.id)) return false;
    }
    add_triangles(frame);
    return true;
}

void MeshReplica::add_triangles(const DecodedFrame& frame) {
    for (const Vertex& v : frame.vertices) vertices_[v.id] = v;
    for (const FrameTriangle& t : frame.triangles) {
        triangles_.emplace(t.id, t.vertices);
        for (std::uint32_t v : t.vertices) ++uses_[v];
    }
}

}  // namespace isomesh::protocol
