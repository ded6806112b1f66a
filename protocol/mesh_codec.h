// The mesh payload of binary frames: a set of triangles over globally numbered vertices, as a
// Draco-compressed mesh (PROTOCOL.md, "The mesh payload").
//
// - Connectivity: Draco's edgebreaker (Rossignac 1999, "Edgebreaker: connectivity compression for
//   triangle meshes"). It reorders the triangles, so the encoder reports where each input triangle
//   landed in the decoded mesh: frames number triangles by that order.
// - Positions: quantized on a grid fixed for the whole session (origin, range, bits), so a vertex
//   sent in two payloads decodes to the same bits in both: shared edges never crack.
// - Normals: octahedral (Meyer et al. 2010, "On floating-point normal vectors").
// - Global vertex ids: a lossless uint32 GENERIC attribute whose attribute metadata has the entry
//   name = "global_id"; clients weld vertices by it.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/vec3.hpp>

#include "protocol/errors.h"

namespace isomesh::protocol {

/// Draco attribute unique ids and the metadata entry naming the global id attribute.
inline constexpr std::uint32_t kPositionAttributeUniqueId = 0;
inline constexpr std::uint32_t kNormalAttributeUniqueId = 1;
inline constexpr std::uint32_t kGlobalIdAttributeUniqueId = 2;
inline constexpr const char* kGlobalIdMetadataKey = "name";
inline constexpr const char* kGlobalIdMetadataValue = "global_id";
/// Version-2 payloads: the normal attribute (unique id 1) is GENERIC int16 x 2, octahedral codes
/// (delta_v2_geometry.h), named by this metadata value (entry `name`).
inline constexpr const char* kOctahedralNormalMetadataValue = "octahedral_normal";

/// A vertex with its session-wide id. `normal` is a unit vector, or zero where the surface has
/// none (a zero normal decodes as (1, 0, 0)).
struct Vertex {
    std::uint32_t id = 0;
    glm::vec3 position{0.0f};
    glm::vec3 normal{0.0f};
    friend bool operator==(const Vertex&, const Vertex&) = default;
};

/// A triangle by the global ids of its vertices, counter-clockwise seen from outside.
struct Triangle {
    std::array<std::uint32_t, 3> vertices{};
    friend bool operator==(const Triangle&, const Triangle&) = default;
};

/// The corners rotated to start at the smallest id, orientation kept. Decoding may rotate a
/// triangle's corners (never mirror them): compare triangles by this form.
std::array<std::uint32_t, 3> canonical_rotation(const std::array<std::uint32_t, 3>& vertices);

/// The fixed position grid of a session: positions are clamped to the cube [origin, origin +
/// range]^3 and rounded to one of 2^bits - 1 steps per axis.
struct QuantizationGrid {
    glm::vec3 origin{0.0f};
    float range = 1.0f;
    int position_bits = 14;  ///< 1..30
    int normal_bits = 10;    ///< 2..30

    /// The grid of a session box [x0, x1, y0, y1, z0, z1]: a cube around the box with a margin of
    /// 1/64 of its largest extent on every side, for vertices projected slightly outside it.
    static QuantizationGrid for_box(const std::array<double, 6>& box, int position_bits = 14);
};

/// Draco's speed settings (0 = smallest output, 10 = fastest; decoders do not depend on them).
/// Speed 2 measured smallest or nearly so on both synthetic and real refinement deltas: 10% to 20%
/// fewer bytes than Draco's default 5 (isomesh-protocol-sample stats; figures in PROTOCOL.md).
struct MeshEncoding {
    QuantizationGrid grid;
    int encoding_speed = 2;
    int decoding_speed = 2;
    /// Version-2 payloads: normals as octahedral codes on grid.normal_bits (exact integers).
    bool octahedral_normals = false;
};

struct EncodedMesh {
    std::vector<std::uint8_t> bytes;
    /// decoded_index[i]: the position of input triangle i in the decoded mesh.
    std::vector<std::uint32_t> decoded_index;
    /// Number of Draco points of the payload (>= distinct vertices: edgebreaker may split
    /// non-manifold vertices).
    std::uint32_t point_count = 0;
};

/// Encodes `triangles` (at least one). `vertices` must hold every vertex the triangles use, once
/// (extra vertices are ignored); every position must be finite. Fails (bad_field) on a missing or
/// repeated vertex id, a triangle that repeats a vertex, or a non-finite position.
Result<EncodedMesh> encode_mesh(std::span<const Vertex> vertices,
                                std::span<const Triangle> triangles, const MeshEncoding& encoding);

struct DecodedMesh {
    std::vector<Vertex> vertices;     ///< distinct global ids, in order of first use
    std::vector<Triangle> triangles;  ///< in decoded order
    std::uint32_t point_count = 0;    ///< Draco points, before welding by global id
};

/// Decodes a payload made by encode_mesh (or any Draco mesh with the same attributes). Fails
/// (bad_frame) on anything else: not Draco, not a triangle mesh, missing or mistyped attributes,
/// a triangle that repeats a vertex, one global id with two different positions or normals.
/// `grid`: for a version-2 payload, the grid whose normal bits its octahedral normals use.
Result<DecodedMesh> decode_mesh(std::span<const std::uint8_t> bytes,
                                const QuantizationGrid* grid = nullptr);

}  // namespace isomesh::protocol
