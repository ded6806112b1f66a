// Binary frames: the mesh data of the isomesh protocol (PROTOCOL.md, "Binary frames").
//
// A frame is a fixed 76-byte little-endian header, then three sections whose lengths the header
// gives: removed triangle ids (sorted, delta-coded varints), explicit triangle ids (optional,
// zigzag delta-coded varints), and the mesh payload of added triangles (Draco, mesh_codec.h).
// Vertices that move (a new function version) travel with re-sent triangles: a delta removes the
// triangles around them and adds them again, and a vertex id a client knows takes the new values.
//
//   offset size field
//        0    4 magic "ISOM"
//        4    1 protocol version (1)
//        5    1 kind: 1 keyframe, 2 delta
//        6    2 flags (bit 0 converged, bit 1 catch_up; other bits 0, ignored by readers)
//        8   16 session id
//       24    8 sequence number
//       32    8 server timestamp, microseconds since the Unix epoch
//       40    8 base triangle id
//       48    4 function version
//       52    4 removed triangle count
//       56    4 added triangle count
//       60    4 mesh payload point count
//       64    4 removed ids length in bytes
//       68    4 explicit triangle ids length in bytes (0: ids are base + decoded index)
//       72    4 mesh payload length in bytes
//
// Protocol version 2 (PROTOCOL.md 4.5) keeps this layout for keyframes, with version byte 2 and a
// 20-byte block after the header giving the session's quantization grid; its deltas are a 56-byte
// header and a range-coded body (delta_v2.h).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "protocol/errors.h"
#include "protocol/mesh_codec.h"
#include "protocol/messages.h"

namespace isomesh::protocol {

inline constexpr std::size_t kFrameHeaderBytes = 76;
/// Version-2 keyframes: the grid block after the header (origin xyz and range as float32, position
/// bits, normal bits, two zero bytes).
inline constexpr std::size_t kGridBlockBytes = 20;
/// Version-2 deltas: magic, version, kind, flags, session, sequence, timestamp, base triangle id,
/// function version, base vertex id.
inline constexpr std::size_t kDeltaV2HeaderBytes = 56;
inline constexpr std::array<std::uint8_t, 4> kFrameMagic = {'I', 'S', 'O', 'M'};
/// Triangle ids stay below 2^53 so that JavaScript clients can hold them in Numbers.
inline constexpr std::uint64_t kMaxTriangleId = (std::uint64_t{1} << 53) - 1;
/// Most triangles (added or removed) in one frame: bounds what a decoder allocates.
inline constexpr std::uint32_t kMaxFrameTriangles = 1u << 22;

enum class FrameKind : std::uint8_t { keyframe = 1, delta = 2 };

namespace frame_flags {
/// After this frame the session's mesh meets its constraints for this function version.
inline constexpr std::uint16_t converged = 1 << 0;
/// A keyframe sent in place of deltas this connection missed (resync or backpressure).
inline constexpr std::uint16_t catch_up = 1 << 1;
}  // namespace frame_flags

/// What the server knows about a frame besides its triangles.
struct FrameInfo {
    FrameKind kind = FrameKind::delta;
    std::uint16_t flags = 0;
    SessionId session;
    std::uint64_t sequence = 0;
    std::uint64_t timestamp_us = 0;
    std::uint32_t function_version = 1;
    /// 1 or 2 (kProtocolVersion, kMaxProtocolVersion).
    std::uint8_t protocol_version = 1;
    friend bool operator==(const FrameInfo&, const FrameInfo&) = default;
};

/// The whole header: the frame's info, its id base, counts and section lengths.
struct FrameHeader : FrameInfo {
    std::uint64_t base_triangle_id = 0;
    std::uint32_t removed_count = 0;
    std::uint32_t triangle_count = 0;
    std::uint32_t point_count = 0;
    std::uint32_t removed_bytes = 0;
    std::uint32_t triangle_ids_bytes = 0;
    std::uint32_t mesh_bytes = 0;
    /// Version-2 deltas: the global id of the first vertex the delta adds.
    std::uint32_t base_vertex_id = 0;
    /// Version-2 keyframes: the grid the session's later version-2 deltas quantize positions on.
    QuantizationGrid grid;
    friend bool operator==(const FrameHeader& a, const FrameHeader& b) {
        return static_cast<const FrameInfo&>(a) == static_cast<const FrameInfo&>(b) &&
               a.base_triangle_id == b.base_triangle_id && a.removed_count == b.removed_count &&
               a.triangle_count == b.triangle_count && a.point_count == b.point_count &&
               a.removed_bytes == b.removed_bytes && a.triangle_ids_bytes == b.triangle_ids_bytes &&
               a.mesh_bytes == b.mesh_bytes && a.base_vertex_id == b.base_vertex_id &&
               a.grid.origin == b.grid.origin && a.grid.range == b.grid.range &&
               a.grid.position_bits == b.grid.position_bits &&
               a.grid.normal_bits == b.grid.normal_bits;
    }
};

void write_frame_header(const FrameHeader& header, std::span<std::uint8_t, kFrameHeaderBytes> out);
/// The header of a version-2 delta (its counts are in the body: delta_v2.h).
void write_delta_v2_header(const FrameHeader& header,
                           std::span<std::uint8_t, kDeltaV2HeaderBytes> out);

/// A copy of a frame (at least its header) naming `session` instead: what holders of a session's
/// view id receive.
std::vector<std::uint8_t> with_session(std::span<const std::uint8_t> frame,
                                       const SessionId& session);
/// The same, stamped `timestamp_us` too: a frame made for another session (the first mesh of a
/// request, server/first_mesh_cache.h).
std::vector<std::uint8_t> with_session(std::span<const std::uint8_t> frame,
                                       const SessionId& session, std::uint64_t timestamp_us);

/// The sequence number in a frame's header (0 for anything shorter than 32 bytes).
std::uint64_t frame_sequence(std::span<const std::uint8_t> frame);

/// Reads and validates a header (for a version-2 delta, its 56 bytes only): magic, version, kind,
/// count limits, a keyframe removing nothing,
/// the implicit id range base + count staying <= kMaxTriangleId, and mesh_bytes = 0 exactly when
/// triangle_count = 0. Section lengths are checked against the frame by decode_frame.
Result<FrameHeader> read_frame_header(std::span<const std::uint8_t> frame);

struct EncodedFrame {
    std::vector<std::uint8_t> bytes;
    /// The wire id given to each input triangle (deltas: base + its decoded index).
    std::vector<std::uint64_t> triangle_ids;
};

/// What a delta changes, applied in this order: triangles removed, then triangles added with the
/// vertices they use.
struct DeltaContent {
    std::span<const std::uint64_t> removed;  ///< any order, distinct, each <= kMaxTriangleId
    std::span<const Vertex> vertices;        ///< every vertex `triangles` use (extra ones ignored)
    std::span<const Triangle> triangles;     ///< get the ids base_triangle_id + decoded index
    std::uint64_t base_triangle_id = 0;
};

/// Precondition: info.kind == delta. Fails (bad_field) on invalid content, e.g. added ids that
/// would pass kMaxTriangleId.
Result<EncodedFrame> encode_delta(const FrameInfo& info, const DeltaContent& content,
                                  const MeshEncoding& encoding);

/// A keyframe: the whole mesh, each triangle keeping its id (`triangle_ids[i]` for triangles[i],
/// distinct, each <= kMaxTriangleId). Precondition: info.kind == keyframe. A version-2 keyframe
/// (info.protocol_version 2) carries encoding.grid in its grid block.
Result<EncodedFrame> encode_keyframe(const FrameInfo& info, std::span<const Vertex> vertices,
                                     std::span<const Triangle> triangles,
                                     std::span<const std::uint64_t> triangle_ids,
                                     const MeshEncoding& encoding);

/// A keyframe whose triangles take the ids base_triangle_id + their index in the decoded mesh, so
/// that it carries no id section (section B): out.triangle_ids[i] is triangles[i]'s id. For a mesh
/// no client holds yet (its ids are free to choose).
Result<EncodedFrame> encode_keyframe_numbered(const FrameInfo& info,
                                              std::span<const Vertex> vertices,
                                              std::span<const Triangle> triangles,
                                              std::uint64_t base_triangle_id,
                                              const MeshEncoding& encoding);

struct FrameTriangle {
    std::uint64_t id = 0;
    std::array<std::uint32_t, 3> vertices{};  ///< global vertex ids
    friend bool operator==(const FrameTriangle&, const FrameTriangle&) = default;
};

struct DecodedFrame {
    FrameHeader header;
    std::vector<std::uint64_t> removed;    ///< ascending
    std::vector<Vertex> vertices;          ///< distinct global ids
    std::vector<FrameTriangle> triangles;  ///< in decoded order, with their wire ids
};

/// Decodes and validates a whole frame; fails with bad_frame (or unsupported_version) on any
/// inconsistency: lengths, counts, id ranges and duplicates, the mesh payload. A version-2 delta
/// is decoded against the mesh it applies to instead (decode_delta_v2, delta_v2.h): here it fails
/// with bad_frame.
Result<DecodedFrame> decode_frame(std::span<const std::uint8_t> frame);

}  // namespace isomesh::protocol
