// Writing and validating binary frames (layout in frame.h; PROTOCOL.md, "Binary frames").
#include "protocol/frame.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <string>

#include "protocol/varint.h"

namespace isomesh::protocol {
namespace {

Error frame_error(std::string message) {
    return Error{ErrorCode::bad_frame, std::move(message)};
}
Error field_error(std::string message) {
    return Error{ErrorCode::bad_field, std::move(message)};
}

template <class T>
void put(std::span<std::uint8_t> out, std::size_t offset, T value) {
    for (std::size_t i = 0; i < sizeof(T); ++i) {
        out[offset + i] = static_cast<std::uint8_t>(static_cast<std::uint64_t>(value) >> (8 * i));
    }
}

template <class T>
T get(std::span<const std::uint8_t> in, std::size_t offset) {
    std::uint64_t value = 0;
    for (std::size_t i = 0; i < sizeof(T); ++i) {
        value |= static_cast<std::uint64_t>(in[offset + i]) << (8 * i);
    }
    return static_cast<T>(value);
}

float get_float(std::span<const std::uint8_t> in, std::size_t offset) {
    return std::bit_cast<float>(get<std::uint32_t>(in, offset));
}

void put_float(std::span<std::uint8_t> out, std::size_t offset, float value) {
    put(out, offset, std::bit_cast<std::uint32_t>(value));
}

/// The grid block of a version-2 keyframe (frame.h).
std::array<std::uint8_t, kGridBlockBytes> grid_block(const QuantizationGrid& grid) {
    std::array<std::uint8_t, kGridBlockBytes> out{};
    for (int axis = 0; axis < 3; ++axis) put_float(out, 4 * axis, grid.origin[axis]);
    put_float(out, 12, grid.range);
    out[16] = static_cast<std::uint8_t>(grid.position_bits);
    out[17] = static_cast<std::uint8_t>(grid.normal_bits);
    return out;
}

Result<QuantizationGrid> read_grid_block(std::span<const std::uint8_t> in) {
    QuantizationGrid grid;
    for (int axis = 0; axis < 3; ++axis) grid.origin[axis] = get_float(in, 4 * axis);
    grid.range = get_float(in, 12);
    grid.position_bits = in[16];
    grid.normal_bits = in[17];
    const bool finite = std::isfinite(grid.origin.x) && std::isfinite(grid.origin.y) &&
                        std::isfinite(grid.origin.z) && std::isfinite(grid.range);
    if (!finite || !(grid.range > 0.0f) || grid.position_bits < 1 || grid.position_bits > 30 ||
        grid.normal_bits < 2 || grid.normal_bits > 30) {
        return frame_error("invalid quantization grid");
    }
    return grid;
}

/// The 56-byte header of a version-2 delta (after the shared first 24 bytes).
FrameHeader read_delta_v2_header(std::span<const std::uint8_t> in, FrameHeader h) {
    h.base_triangle_id = get<std::uint64_t>(in, 40);
    h.function_version = get<std::uint32_t>(in, 48);
    h.base_vertex_id = get<std::uint32_t>(in, 52);
    return h;
}

/// Checks that `ids` are distinct and in range; returns them sorted.
Result<std::vector<std::uint64_t>> sorted_distinct(std::span<const std::uint64_t> ids,
                                                   const char* what) {
    std::vector<std::uint64_t> sorted(ids.begin(), ids.end());
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) {
        return field_error(std::string(what) + " ids repeat");
    }
    if (!sorted.empty() && sorted.back() > kMaxTriangleId) {
        return field_error(std::string(what) + " id exceeds 2^53 - 1");
    }
    return sorted;
}

std::optional<Error> check_frame_count(std::size_t count, const char* what) {
    if (count > kMaxFrameTriangles) {
        return field_error(std::string("more than 2^22 ") + what + " triangles in one frame");
    }
    return std::nullopt;
}

FrameHeader header_for(const FrameInfo& info) {
    FrameHeader header;
    static_cast<FrameInfo&>(header) = info;
    return header;
}

/// The encoded sections of a frame, in frame order.
struct Sections {
    std::vector<std::uint8_t> removed;
    std::vector<std::uint8_t> triangle_ids;
    EncodedMesh mesh;
};

std::vector<std::uint8_t> assemble(FrameHeader header, const Sections& s,
                                   const QuantizationGrid& grid) {
    header.removed_bytes = static_cast<std::uint32_t>(s.removed.size());
    header.triangle_ids_bytes = static_cast<std::uint32_t>(s.triangle_ids.size());
    header.mesh_bytes = static_cast<std::uint32_t>(s.mesh.bytes.size());
    header.point_count = s.mesh.point_count;
    std::vector<std::uint8_t> frame(kFrameHeaderBytes);
    write_frame_header(header, std::span<std::uint8_t, kFrameHeaderBytes>(frame));
    if (header.protocol_version == 2) {
        const auto block = grid_block(grid);
        frame.insert(frame.end(), block.begin(), block.end());
    }
    for (const auto* bytes : {&s.removed, &s.triangle_ids, &s.mesh.bytes}) {
        frame.insert(frame.end(), bytes->begin(), bytes->end());
    }
    return frame;
}

Result<EncodedMesh> encode_if_any(std::span<const Vertex> vertices,
                                  std::span<const Triangle> triangles,
                                  const MeshEncoding& encoding) {
    if (triangles.empty()) return EncodedMesh{};
    return encode_mesh(vertices, triangles, encoding);
}

/// The section of `frame` at `offset` of `length` bytes (bounds checked by the caller).
std::span<const std::uint8_t> section(std::span<const std::uint8_t> frame, std::size_t& offset,
                                      std::uint32_t length) {
    auto bytes = frame.subspan(offset, length);
    offset += length;
    return bytes;
}

Result<std::vector<std::uint64_t>> decode_triangle_ids(const FrameHeader& header,
                                                       std::span<const std::uint8_t> bytes) {
    if (header.triangle_ids_bytes == 0) {
        std::vector<std::uint64_t> ids(header.triangle_count);
        for (std::uint32_t i = 0; i < header.triangle_count; ++i) {
            ids[i] = header.base_triangle_id + i;
        }
        return ids;
    }
    auto ids =
        decode_id_sequence(bytes, header.triangle_count, header.base_triangle_id, kMaxTriangleId);
    if (!ids) return ids.error();
    if (!sorted_distinct(ids.value(), "triangle")) return frame_error("triangle ids repeat");
    return ids;
}

}  // namespace

void write_delta_v2_header(const FrameHeader& h, std::span<std::uint8_t, kDeltaV2HeaderBytes> out) {
    std::copy(kFrameMagic.begin(), kFrameMagic.end(), out.begin());
    out[4] = 2;
    out[5] = static_cast<std::uint8_t>(FrameKind::delta);
    put(out, 6, h.flags);
    std::copy(h.session.bytes.begin(), h.session.bytes.end(), out.begin() + 8);
    put(out, 24, h.sequence);
    put(out, 32, h.timestamp_us);
    put(out, 40, h.base_triangle_id);
    put(out, 48, h.function_version);
    put(out, 52, h.base_vertex_id);
}

void write_frame_header(const FrameHeader& h, std::span<std::uint8_t, kFrameHeaderBytes> out) {
    std::copy(kFrameMagic.begin(), kFrameMagic.end(), out.begin());
    out[4] = h.protocol_version;
    out[5] = static_cast<std::uint8_t>(h.kind);
    put(out, 6, h.flags);
    std::copy(h.session.bytes.begin(), h.session.bytes.end(), out.begin() + 8);
    put(out, 24, h.sequence);
    put(out, 32, h.timestamp_us);
    put(out, 40, h.base_triangle_id);
    put(out, 48, h.function_version);
    put(out, 52, h.removed_count);
    put(out, 56, h.triangle_count);
    put(out, 60, h.point_count);
    put(out, 64, h.removed_bytes);
    put(out, 68, h.triangle_ids_bytes);
    put(out, 72, h.mesh_bytes);
}

std::vector<std::uint8_t> with_session(std::span<const std::uint8_t> frame,
                                       const SessionId& session) {
    std::vector<std::uint8_t> out(frame.begin(), frame.end());
    std::copy(session.bytes.begin(), session.bytes.end(), out.begin() + 8);
    return out;
}

std::vector<std::uint8_t> with_session(std::span<const std::uint8_t> frame,
                                       const SessionId& session, std::uint64_t timestamp_us) {
    std::vector<std::uint8_t> out = with_session(frame, session);
    put<std::uint64_t>(out, 32, timestamp_us);
    return out;
}

std::uint64_t frame_sequence(std::span<const std::uint8_t> frame) {
    return frame.size() >= 32 ? get<std::uint64_t>(frame, 24) : 0;
}

Result<FrameHeader> read_frame_header(std::span<const std::uint8_t> in) {
    if (in.size() < kDeltaV2HeaderBytes) return frame_error("frame shorter than its header");
    if (!std::equal(kFrameMagic.begin(), kFrameMagic.end(), in.begin())) {
        return frame_error("frame does not start with ISOM");
    }
    const bool short_header = in[4] == 2 && in[5] == static_cast<std::uint8_t>(FrameKind::delta);
    if (!short_header && in.size() < kFrameHeaderBytes)
        return frame_error("frame shorter than its 76-byte header");
    if (in[4] < kProtocolVersion || in[4] > kMaxProtocolVersion) {
        return Error{ErrorCode::unsupported_version,
                     "frame of protocol version " + std::to_string(in[4])};
    }
    if (in[5] != static_cast<std::uint8_t>(FrameKind::keyframe) &&
        in[5] != static_cast<std::uint8_t>(FrameKind::delta)) {
        return frame_error("unknown frame kind " + std::to_string(in[5]));
    }
    FrameHeader h;
    h.protocol_version = in[4];
    h.kind = static_cast<FrameKind>(in[5]);
    h.flags = get<std::uint16_t>(in, 6);
    std::copy_n(in.begin() + 8, 16, h.session.bytes.begin());
    h.sequence = get<std::uint64_t>(in, 24);
    h.timestamp_us = get<std::uint64_t>(in, 32);
    if (h.protocol_version == 2 && h.kind == FrameKind::delta) {
        h = read_delta_v2_header(in, h);
        if (h.function_version == 0) return frame_error("function version 0");
        if (h.base_triangle_id > kMaxTriangleId) return frame_error("triangle ids exceed 2^53 - 1");
        return h;
    }
    h.base_triangle_id = get<std::uint64_t>(in, 40);
    h.function_version = get<std::uint32_t>(in, 48);
    h.removed_count = get<std::uint32_t>(in, 52);
    h.triangle_count = get<std::uint32_t>(in, 56);
    h.point_count = get<std::uint32_t>(in, 60);
    h.removed_bytes = get<std::uint32_t>(in, 64);
    h.triangle_ids_bytes = get<std::uint32_t>(in, 68);
    h.mesh_bytes = get<std::uint32_t>(in, 72);

    if (h.function_version == 0) return frame_error("function version 0");
    if (h.removed_count > kMaxFrameTriangles || h.triangle_count > kMaxFrameTriangles) {
        return frame_error("more than 2^22 triangles in one frame");
    }
    if (h.kind == FrameKind::keyframe && h.removed_count > 0) {
        return frame_error("a keyframe removes nothing");
    }
    if ((h.triangle_count == 0) != (h.mesh_bytes == 0)) {
        return frame_error("mesh payload length disagrees with the triangle count");
    }
    if ((h.triangle_count == 0) != (h.point_count == 0) ||
        h.point_count > std::uint64_t{3} * h.triangle_count) {
        return frame_error("point count disagrees with the triangle count");
    }
    if (h.base_triangle_id > kMaxTriangleId ||
        (h.triangle_ids_bytes == 0 && h.triangle_count > 0 &&
         h.triangle_count - 1 > kMaxTriangleId - h.base_triangle_id)) {
        return frame_error("triangle ids exceed 2^53 - 1");
    }
    if (h.protocol_version == 2) {
        if (in.size() < kFrameHeaderBytes + kGridBlockBytes) {
            return frame_error("version-2 keyframe shorter than its header and grid block");
        }
        auto grid = read_grid_block(in.subspan(kFrameHeaderBytes, kGridBlockBytes));
        if (!grid) return grid.error();
        h.grid = grid.value();
    }
    return h;
}

Result<EncodedFrame> encode_delta(const FrameInfo& info, const DeltaContent& content,
                                  const MeshEncoding& encoding) {
    assert(info.kind == FrameKind::delta && info.protocol_version == 1);
    const auto& triangles = content.triangles;
    const std::uint64_t base = content.base_triangle_id;
    if (auto error = check_frame_count(content.removed.size(), "removed")) return *error;
    if (auto error = check_frame_count(triangles.size(), "added")) return *error;
    if (!triangles.empty() &&
        (base > kMaxTriangleId || triangles.size() - 1 > kMaxTriangleId - base)) {
        return field_error("added triangle ids would exceed 2^53 - 1");
    }
    auto sorted_removed = sorted_distinct(content.removed, "removed");
    if (!sorted_removed) return sorted_removed.error();
    Sections sections;
    sections.removed = encode_sorted_ids(sorted_removed.value());
    auto mesh = encode_if_any(content.vertices, triangles, encoding);
    if (!mesh) return mesh.error();
    sections.mesh = std::move(mesh.value());

    FrameHeader header = header_for(info);
    header.base_triangle_id = base;
    header.removed_count = static_cast<std::uint32_t>(content.removed.size());
    header.triangle_count = static_cast<std::uint32_t>(triangles.size());
    EncodedFrame out;
    out.triangle_ids.resize(triangles.size());
    for (std::size_t i = 0; i < triangles.size(); ++i) {
        out.triangle_ids[i] = base + sections.mesh.decoded_index[i];
    }
    out.bytes = assemble(header, sections, encoding.grid);
    return out;
}

namespace {

/// A keyframe of an encoded mesh whose decoded triangle d has id ids_in_decoded_order[d]: no id
/// section when those are consecutive.
EncodedFrame assemble_keyframe(const FrameInfo& info, EncodedMesh mesh,
                               const std::vector<std::uint64_t>& ids_in_decoded_order,
                               const QuantizationGrid& grid) {
    FrameHeader header = header_for(info);
    header.triangle_count = static_cast<std::uint32_t>(ids_in_decoded_order.size());
    const bool consecutive =
        std::adjacent_find(ids_in_decoded_order.begin(), ids_in_decoded_order.end(),
                           [](std::uint64_t a, std::uint64_t b) { return b != a + 1; }) ==
        ids_in_decoded_order.end();
    Sections sections;
    if (consecutive && !ids_in_decoded_order.empty()) {
        header.base_triangle_id = ids_in_decoded_order.front();
    } else {
        sections.triangle_ids = encode_id_sequence(ids_in_decoded_order, 0);
    }
    sections.mesh = std::move(mesh);
    EncodedFrame out;
    out.bytes = assemble(header, sections, grid);
    return out;
}

}  // namespace

Result<EncodedFrame> encode_keyframe(const FrameInfo& info, std::span<const Vertex> vertices,
                                     std::span<const Triangle> triangles,
                                     std::span<const std::uint64_t> triangle_ids,
                                     const MeshEncoding& encoding) {
    assert(info.kind == FrameKind::keyframe);
    if (auto error = check_frame_count(triangles.size(), "added")) return *error;
    if (triangle_ids.size() != triangles.size()) {
        return field_error("a keyframe needs one id per triangle");
    }
    if (auto valid = sorted_distinct(triangle_ids, "triangle"); !valid) return valid.error();
    MeshEncoding versioned = encoding;
    versioned.octahedral_normals = info.protocol_version == 2;
    auto mesh = encode_if_any(vertices, triangles, versioned);
    if (!mesh) return mesh.error();

    std::vector<std::uint64_t> ids_in_decoded_order(triangles.size());
    for (std::size_t i = 0; i < triangles.size(); ++i) {
        ids_in_decoded_order[mesh.value().decoded_index[i]] = triangle_ids[i];
    }
    EncodedFrame out =
        assemble_keyframe(info, std::move(mesh.value()), ids_in_decoded_order, encoding.grid);
    out.triangle_ids.assign(triangle_ids.begin(), triangle_ids.end());
    return out;
}

Result<EncodedFrame> encode_keyframe_numbered(const FrameInfo& info,
                                              std::span<const Vertex> vertices,
                                              std::span<const Triangle> triangles,
                                              std::uint64_t base_triangle_id,
                                              const MeshEncoding& encoding) {
    assert(info.kind == FrameKind::keyframe);
    if (auto error = check_frame_count(triangles.size(), "added")) return *error;
    if (!triangles.empty() && triangles.size() - 1 > kMaxTriangleId - base_triangle_id)
        return field_error("triangle ids would exceed 2^53 - 1");
    MeshEncoding versioned = encoding;
    versioned.octahedral_normals = info.protocol_version == 2;
    auto mesh = encode_if_any(vertices, triangles, versioned);
    if (!mesh) return mesh.error();
    std::vector<std::uint64_t> ids_in_decoded_order(triangles.size());
    for (std::size_t d = 0; d < triangles.size(); ++d)
        ids_in_decoded_order[d] = base_triangle_id + d;
    std::vector<std::uint64_t> triangle_ids(triangles.size());
    for (std::size_t i = 0; i < triangles.size(); ++i)
        triangle_ids[i] = base_triangle_id + mesh.value().decoded_index[i];
    EncodedFrame out =
        assemble_keyframe(info, std::move(mesh.value()), ids_in_decoded_order, encoding.grid);
    out.triangle_ids = std::move(triangle_ids);
    return out;
}

Result<DecodedFrame> decode_frame(std::span<const std::uint8_t> frame) {
    auto header = read_frame_header(frame);
    if (!header) return header.error();
    const FrameHeader& h = header.value();
    if (h.protocol_version == 2 && h.kind == FrameKind::delta) {
        return frame_error("a version-2 delta is decoded against the mesh it applies to");
    }
    const std::size_t start = kFrameHeaderBytes + (h.protocol_version == 2 ? kGridBlockBytes : 0);
    const std::uint64_t expected =
        std::uint64_t{start} + h.removed_bytes + h.triangle_ids_bytes + h.mesh_bytes;
    if (expected != frame.size()) {
        return frame_error("frame of " + std::to_string(frame.size()) + " bytes, header says " +
                           std::to_string(expected));
    }
    std::size_t offset = start;
    const auto removed_section = section(frame, offset, h.removed_bytes);
    const auto ids_section = section(frame, offset, h.triangle_ids_bytes);
    const auto mesh_section = section(frame, offset, h.mesh_bytes);

    DecodedFrame out;
    out.header = h;
    auto removed = decode_sorted_ids(removed_section, h.removed_count, kMaxTriangleId);
    if (!removed) return removed.error();
    out.removed = std::move(removed.value());
    auto ids = decode_triangle_ids(h, ids_section);
    if (!ids) return ids.error();
    if (h.triangle_count == 0) return out;

    auto mesh = decode_mesh(mesh_section, h.protocol_version == 2 ? &h.grid : nullptr);
    if (!mesh) return mesh.error();
    if (mesh.value().triangles.size() != h.triangle_count ||
        mesh.value().point_count != h.point_count) {
        return frame_error("mesh payload counts disagree with the header");
    }
    out.vertices = std::move(mesh.value().vertices);
    out.triangles.reserve(h.triangle_count);
    for (std::size_t i = 0; i < h.triangle_count; ++i) {
        out.triangles.push_back({ids.value()[i], mesh.value().triangles[i].vertices});
    }
    return out;
}

}  // namespace isomesh::protocol
