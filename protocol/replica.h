// A client's copy of one session's mesh, kept by applying decoded frames in order (PROTOCOL.md,
// "Applying frames"): a keyframe replaces everything; a delta with the next sequence number removes
// its triangles, then adds its vertices (a known id takes the new values: that is how vertices
// move) and triangles; stale deltas are skipped; a gap or an inconsistent delta stops the replica
// until the next keyframe, which the client asks for with `resync`.
#pragma once

#include <cstdint>
#include <vector>

#include "protocol/frame.h"
#include "protocol/held_mesh.h"

namespace isomesh::protocol {

class MeshReplica {
  public:
    enum class Outcome {
        applied,
        stale,              ///< a delta at or before the current sequence number: skipped
        awaiting_keyframe,  ///< no keyframe since the start or since a gap: skipped
        gap,                ///< a delta after a missing one: send `resync`
        inconsistent,       ///< removes an unknown triangle or re-adds a known one: send `resync`
    };

    Outcome apply(const DecodedFrame& frame);
    /// Decodes a frame of either protocol version and applies it. A version-2 delta is decoded
    /// against this mesh, so only when it is the next one; one that does not fit is
    /// `inconsistent`. Fails only on a frame whose header is malformed.
    Result<Outcome> receive(std::span<const std::uint8_t> frame);

    bool synchronized() const { return synchronized_; }
    std::uint64_t sequence() const { return sequence_; }
    std::uint32_t function_version() const { return function_version_; }

    std::size_t triangle_count() const { return held_.triangle_count(); }
    std::size_t vertex_count() const { return held_.vertex_count(); }
    const IdTable<std::uint64_t, std::array<std::uint32_t, 3>>& triangles() const {
        return held_.triangles();
    }
    const IdTable<std::uint32_t, Vertex>& vertices() const { return held_.vertices(); }
    const HeldMesh& held() const { return held_; }

    /// The triangles sorted by id, corners in canonical_rotation, for comparing meshes.
    std::vector<FrameTriangle> sorted_triangles() const;

  private:
    /// Where a delta with this header stands against the current sequence number (applied: it is
    /// the next one).
    Outcome place(const FrameHeader& header);
    bool consistent(const DecodedFrame& frame) const;

    bool synchronized_ = false;
    std::uint64_t sequence_ = 0;
    std::uint32_t function_version_ = 0;
    HeldMesh held_;
    QuantizationGrid grid_;  // of the last version-2 keyframe
};

}  // namespace isomesh::protocol
