// Version-2 delta frames: deltas that carry only what the client lacks (PROTOCOL.md 4.5).
//
// A refinement step bisects edges: each new vertex splits an edge (p, q) of the mesh, and the one
// or two triangles holding that edge are replaced by their halves. A version-2 delta says exactly
// that: for each new vertex, a triangle the client holds (by wire id, sorted within a round so the
// ids are small differences) and which of its edges is split (predicted: the edge opposite its
// newest corner, the base edge of newest-vertex bisection), then the vertex's quantized position
// and octahedral normal as residuals of a prediction from the edge's ends (the midpoint bent by
// their normals, and their mean normal). The client derives the removed and added triangles and
// their ids itself. What splits do not explain (merges, a vertex the encoder cannot place) travels
// explicitly: removed triangle ids, loose vertices, added triangles by global vertex ids. Vertices
// that moved (a new function version) carry their new values predicted from their old ones moved
// along their normals, by the distance the vertex before them moved.
// Everything after the 56-byte header is one range-coded stream (range_coder.h).
//
// The encoder runs the client's decoding on its own copy of the client's mesh, so what it sends is
// what the client ends up with by construction; inferring the splits from a net delta (the
// refiner reports added vertices and triangles, not which edge each vertex split) only decides
// how compact it is. New vertices get their global ids from the frame: base vertex id + their
// order in it.
#pragma once

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "protocol/frame.h"
#include "protocol/held_mesh.h"

namespace isomesh::protocol {

/// A delta to encode, in the ids the client holds.
struct DeltaV2Change {
    std::vector<std::uint64_t> removed;  ///< held triangle ids, distinct
    /// Vertices the delta adds, under provisional ids >= the frame's base vertex id, ascending in
    /// the order they were made (a split's vertex after the vertices of the edge it splits).
    std::vector<Vertex> new_vertices;
    std::vector<Vertex> moved_vertices;  ///< held vertices with new values
    std::vector<Triangle> added;         ///< corners: held or new (provisional) vertex ids
};

/// Where the bits of a delta went (information content of the coded bits) and how it was said.
struct DeltaV2Stats {
    std::size_t splits = 0;
    std::size_t rounds = 0;
    std::size_t loose_vertices = 0;
    std::size_t explicit_removed = 0;
    std::size_t explicit_added = 0;
    std::size_t moved = 0;
    double split_reference_bits = 0;  ///< triangle and edge of each split
    double position_bits = 0;         ///< split vertices' positions
    double normal_bits = 0;           ///< split vertices' normals
    double explicit_bits = 0;         ///< removals, loose vertices, added triangles
    double moved_bits = 0;
};

struct EncodedDeltaV2 {
    std::vector<std::uint8_t> bytes;
    std::vector<std::uint64_t> triangle_ids;  ///< the wire id of each `added` triangle
    std::vector<std::uint32_t> vertex_ids;    ///< the global id of each `new_vertices` vertex
    /// Held triangles the delta removed and added again under a new wire id (old, new).
    std::vector<std::pair<std::uint64_t, std::uint64_t>> renamed;
    /// What a client decodes from `bytes`: apply it to the held mesh to follow the client.
    DecodedFrame applied;
    std::uint64_t next_triangle_id = 0;  ///< past every triangle id the frame used
    std::uint32_t next_vertex_id = 0;    ///< past every vertex id the frame used
    DeltaV2Stats stats;
};

/// Encodes `change` against `held` (the mesh every recipient holds). info.kind must be delta and
/// info.protocol_version 2; triangles the frame makes get ids from base_triangle_id on, vertices
/// from base_vertex_id on (provisional new vertex ids must be base_vertex_id + i, in order).
/// Fails (bad_field) on a change that does not apply to `held`.
Result<EncodedDeltaV2> encode_delta_v2(const FrameInfo& info, const HeldMesh& held,
                                       const DeltaV2Change& change, std::uint64_t base_triangle_id,
                                       std::uint32_t base_vertex_id, const QuantizationGrid& grid);

/// Decodes a version-2 delta against the mesh it applies to (the session's mesh after the frame
/// before it) on the grid of the session's last keyframe. The result is what applying the frame
/// changes: held triangles removed (ascending), the triangles added with their ids, and the values
/// of every vertex they use and of every moved vertex. Fails with bad_frame on a malformed frame
/// and on one that does not fit `held` (a client treats both as a gap: resync).
Result<DecodedFrame> decode_delta_v2(std::span<const std::uint8_t> frame, const HeldMesh& held,
                                     const QuantizationGrid& grid);

}  // namespace isomesh::protocol
