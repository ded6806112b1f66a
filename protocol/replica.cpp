// Applying frames to a client-side mesh (see replica.h). Vertices are dropped when no triangle uses
// them (HeldMesh): every payload carries all vertices its triangles use that the client may lack.
#include "protocol/replica.h"

#include <algorithm>

#include "protocol/delta_v2.h"

namespace isomesh::protocol {

MeshReplica::Outcome MeshReplica::place(const FrameHeader& h) {
    if (!synchronized_) return Outcome::awaiting_keyframe;
    if (h.sequence <= sequence_) return Outcome::stale;
    if (h.sequence != sequence_ + 1) {
        synchronized_ = false;
        return Outcome::gap;
    }
    return Outcome::applied;
}

MeshReplica::Outcome MeshReplica::apply(const DecodedFrame& frame) {
    const FrameHeader& h = frame.header;
    if (h.kind == FrameKind::keyframe) {
        held_.apply(frame);
        if (h.protocol_version == 2) grid_ = h.grid;
        synchronized_ = true;
        sequence_ = h.sequence;
        function_version_ = h.function_version;
        return Outcome::applied;
    }
    if (const Outcome placed = place(h); placed != Outcome::applied) return placed;
    if (!consistent(frame)) {
        synchronized_ = false;
        return Outcome::inconsistent;
    }
    held_.apply(frame);
    sequence_ = h.sequence;
    function_version_ = h.function_version;
    return Outcome::applied;
}

Result<MeshReplica::Outcome> MeshReplica::receive(std::span<const std::uint8_t> bytes) {
    auto header = read_frame_header(bytes);
    if (!header) return header.error();
    const FrameHeader& h = header.value();
    if (h.protocol_version == 2 && h.kind == FrameKind::delta) {
        if (const Outcome placed = place(h); placed != Outcome::applied) return placed;
        auto frame = decode_delta_v2(bytes, held_, grid_);
        if (!frame) {
            synchronized_ = false;
            return Outcome::inconsistent;
        }
        return apply(frame.value());
    }
    auto frame = decode_frame(bytes);
    if (!frame) return frame.error();
    return apply(frame.value());
}

std::vector<FrameTriangle> MeshReplica::sorted_triangles() const {
    std::vector<FrameTriangle> out;
    out.reserve(held_.triangle_count());
    for (const auto& [id, vertices] : held_.triangles())
        out.push_back({id, canonical_rotation(vertices)});
    std::sort(out.begin(), out.end(),
              [](const FrameTriangle& a, const FrameTriangle& b) { return a.id < b.id; });
    return out;
}

bool MeshReplica::consistent(const DecodedFrame& frame) const {
    if (!std::all_of(frame.removed.begin(), frame.removed.end(),
                     [&](std::uint64_t id) { return held_.triangle(id) != nullptr; }))
        return false;
    const std::vector<std::uint64_t>& removed = frame.removed;  // ascending
    return std::all_of(frame.triangles.begin(), frame.triangles.end(), [&](const FrameTriangle& t) {
        return !held_.triangle(t.id) || std::binary_search(removed.begin(), removed.end(), t.id);
    });
}

}  // namespace isomesh::protocol
