// The mesh a client holds for one session: triangles by wire id, vertices by global id, and each
// vertex's star (the triangles using it). Version-2 deltas are decoded against it (a split names a
// held triangle; its partner across the split edge is found through the star), and the server
// keeps one per session as the mirror its version-2 encoder writes against.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <absl/container/flat_hash_map.h>

#include "protocol/frame.h"

namespace isomesh::protocol {

/// Hash tables by triangle or vertex id: Abseil's Swiss tables (open addressing, no allocation per
/// entry; the node-based std::unordered_map's lookups and allocations were most of a version-2
/// delta's encoding time). Iteration order is unspecified and changes from run to run: nothing
/// that reaches a frame may depend on it. References into a table last until it next changes.
template <class Key, class Value>
using IdTable = absl::flat_hash_map<Key, Value>;

class HeldMesh {
  public:
    using Corners = std::array<std::uint32_t, 3>;

    /// The corners of triangle `id`, or nullptr.
    const Corners* triangle(std::uint64_t id) const;
    /// Vertex `id`, or nullptr.
    const Vertex* vertex(std::uint32_t id) const;
    /// The triangles using vertex `id` (empty for an unknown vertex).
    std::span<const std::uint64_t> star(std::uint32_t id) const;

    /// A keyframe's content replaces everything; a delta's is applied in the order of
    /// PROTOCOL.md 6.2 (removals, vertex values, additions). Vertices no triangle uses are dropped.
    /// Precondition: the frame is consistent with this mesh (MeshReplica checks).
    void apply(const DecodedFrame& frame);
    void clear();

    std::size_t triangle_count() const { return triangles_.size(); }
    std::size_t vertex_count() const { return vertices_.size(); }
    const IdTable<std::uint64_t, Corners>& triangles() const { return triangles_; }
    const IdTable<std::uint32_t, Vertex>& vertices() const { return vertices_; }

  private:
    void remove(std::uint64_t id);
    void add(std::uint64_t id, const Corners& corners);

    IdTable<std::uint64_t, Corners> triangles_;
    IdTable<std::uint32_t, Vertex> vertices_;
    IdTable<std::uint32_t, std::vector<std::uint64_t>> stars_;
};

}  // namespace isomesh::protocol
