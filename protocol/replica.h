// A client's copy of one session's mesh, kept by applying decoded frames in order (PROTOCOL.md,
// "Applying frames"): a keyframe replaces everything; a delta with the next sequence number removes
// its triangles, then adds its vertices (a known id takes the new values: that is how vertices
// move) and triangles; stale deltas are skipped; a gap or an inconsistent delta stops the replica
// until the next keyframe, which the client asks for with `resync`.
#pragma once

#include <cstdint>
#include <unordered_map>
#include <vector>

#include "protocol/frame.h"

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

    bool synchronized() const { return synchronized_; }
    std::uint64_t sequence() const { return sequence_; }
    std::uint32_t function_version() const { return function_version_; }

    std::size_t triangle_count() const { return triangles_.size(); }
    std::size_t vertex_count() const { return vertices_.size(); }
    const std::unordered_map<std::uint64_t, std::array<std::uint32_t, 3>>& triangles() const {
        return triangles_;
    }
    const std::unordered_map<std::uint32_t, Vertex>& vertices() const { return vertices_; }

    /// The triangles sorted by id, corners in canonical_rotation, for comparing meshes.
    std::vector<FrameTriangle> sorted_triangles() const;

  private:
    void reset();
    bool apply_delta(const DecodedFrame& frame);
    void add_triangles(const DecodedFrame& frame);

    bool synchronized_ = false;
    std::uint64_t sequence_ = 0;
    std::uint32_t function_version_ = 0;
    std::unordered_map<std::uint64_t, std::array<std::uint32_t, 3>> triangles_;
    std::unordered_map<std::uint32_t, Vertex> vertices_;
    std::unordered_map<std::uint32_t, std::uint32_t> uses_;
};

}  // namespace isomesh::protocol
