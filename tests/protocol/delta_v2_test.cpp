// Version-2 deltas (protocol/delta_v2.h): what the encoder sends decodes to what it says the client
// holds, splits are said as splits, and what they do not explain travels explicitly.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>

#include "protocol/delta_v2.h"
#include "protocol/delta_v2_geometry.h"
#include "protocol/range_coder.h"
#include "protocol/tools/octahedron.h"
#include "protocol/tools/sample_mesh.h"

namespace isomesh::protocol {
namespace {

using Corners = std::array<std::uint32_t, 3>;

FrameInfo delta_info(std::uint64_t sequence) {
    FrameInfo info;
    info.kind = FrameKind::delta;
    info.sequence = sequence;
    info.timestamp_us = 1'700'000'000'000'000;
    info.protocol_version = 2;
    return info;
}

std::vector<Corners> canonical(const HeldMesh& mesh) {
    std::vector<Corners> out;
    for (const auto& [id, c] : mesh.triangles()) out.push_back(canonical_rotation(c));
    std::sort(out.begin(), out.end());
    return out;
}

/// Encodes `change`, decodes the bytes against the same mesh, checks both agree, applies.
EncodedDeltaV2 round_trip(HeldMesh& mesh, const DeltaV2Change& change, std::uint64_t base_triangle,
                          std::uint32_t base_vertex) {
    const QuantizationGrid grid = samples::octahedron_grid();
    auto encoded = encode_delta_v2(delta_info(1), mesh, change, base_triangle, base_vertex, grid);
    if (!encoded.ok()) {
        ADD_FAILURE() << encoded.error().message;
        return {};
    }
    auto decoded = decode_delta_v2(encoded.value().bytes, mesh, grid);
    if (!decoded.ok()) {
        ADD_FAILURE() << decoded.error().message;
        return encoded.value();
    }
    EXPECT_EQ(decoded.value().removed, encoded.value().applied.removed);
    EXPECT_EQ(decoded.value().triangles, encoded.value().applied.triangles);
    EXPECT_EQ(decoded.value().vertices, encoded.value().applied.vertices);
    mesh.apply(decoded.value());
    return encoded.value();
}

TEST(RangeCoder, integers_and_bits_round_trip) {
    RangeEncoder encoder;
    IntModel model;
    BitModel bit;
    const std::vector<std::int64_t> values = {0, 1, -1, 2, 1000, -123456, INT64_C(1) << 50,
                                              0, 0, 7};
    for (std::int64_t v : values) encoder.sint(model, v);
    for (int i = 0; i < 100; ++i) encoder.bit(bit, i % 7 == 0);
    encoder.direct(0xDEADBEEF, 32);
    const auto bytes = encoder.finish();
    RangeDecoder decoder(bytes);
    IntModel model2;
    BitModel bit2;
    for (std::int64_t v : values) EXPECT_EQ(decoder.sint(model2), v);
    for (int i = 0; i < 100; ++i) EXPECT_EQ(decoder.bit(bit2), i % 7 == 0);
    EXPECT_EQ(decoder.direct(32), 0xDEADBEEFu);
    EXPECT_TRUE(decoder.ok());
}

TEST(DeltaV2, a_split_is_said_as_a_split_and_decodes_to_its_halves) {
    HeldMesh mesh = samples::octahedron();
    DeltaV2Change change;
    change.removed = {0, 4};  // (0, 2, 4) and (2, 0, 5) share the edge 0-2
    change.new_vertices = {{6, glm::vec3(0.7071f, 0.7071f, 0.0f), glm::vec3(0.7071f, 0.7071f, 0)}};
    change.added = {{{0, 6, 4}}, {{6, 2, 4}}, {{2, 6, 5}}, {{6, 0, 5}}};
    const EncodedDeltaV2 e = round_trip(mesh, change, 8, 6);
    EXPECT_EQ(e.stats.splits, 1u);
    EXPECT_EQ(e.stats.loose_vertices + e.stats.explicit_added + e.stats.explicit_removed, 0u);
    EXPECT_EQ(mesh.triangle_count(), 10u);
    EXPECT_NEAR(mesh.vertex(6)->position.x, 0.7071f, 1e-3);
    EXPECT_EQ(std::set<std::uint64_t>(e.triangle_ids.begin(), e.triangle_ids.end()).size(), 4u);
    EXPECT_LE(e.bytes.size(), kDeltaV2HeaderBytes + 16);  // 5 of them flush the coder

    // Nested splits in one delta: 6-4 (a child's edge), then 7-4.
    DeltaV2Change nested;
    const auto id_of = [&](const Corners& c) {
        for (const auto& [id, t] : mesh.triangles())
            if (canonical_rotation(t) == canonical_rotation(c)) return id;
        ADD_FAILURE() << "no such triangle";
        return std::uint64_t{0};
    };
    nested.removed = {id_of({0, 6, 4}), id_of({6, 2, 4})};
    nested.new_vertices = {{7, glm::vec3(0.4f, 0.4f, 0.8f), glm::vec3(0.4f, 0.4f, 0.8f)},
                           {8, glm::vec3(0.2f, 0.2f, 0.95f), glm::vec3(0.2f, 0.2f, 0.95f)}};
    nested.added = {{{0, 6, 7}}, {{7, 2, 4}}, {{0, 7, 8}}, {{0, 8, 4}}, {{6, 2, 7}}};
    // (0, 6, 4) -> (0, 6, 7), (0, 7, 4) -> (0, 7, 8), (0, 8, 4); (6, 2, 4) -> (6, 2, 7), (7, 2, 4)
    const EncodedDeltaV2 n = round_trip(mesh, nested, e.next_triangle_id, e.next_vertex_id);
    EXPECT_EQ(n.stats.splits + n.stats.loose_vertices, 2u);
    EXPECT_EQ(mesh.triangle_count(), 13u);
}

TEST(DeltaV2, what_splits_do_not_explain_travels_explicitly_and_moves_apply) {
    HeldMesh mesh = samples::octahedron();
    const std::vector<Corners> before = canonical(mesh);
    DeltaV2Change split;
    split.removed = {0, 4};
    split.new_vertices = {{6, glm::vec3(0.7f, 0.7f, 0.0f), glm::vec3(1, 1, 0)}};
    split.added = {{{0, 6, 4}}, {{6, 2, 4}}, {{2, 6, 5}}, {{6, 0, 5}}};
    const EncodedDeltaV2 e = round_trip(mesh, split, 8, 6);
    // A merge: the four halves go, their parents come back (explicitly), and vertex 4 moves.
    DeltaV2Change merge;
    for (std::uint64_t id : e.triangle_ids) merge.removed.push_back(id);
    merge.added = {{{0, 2, 4}}, {{2, 0, 5}}};
    merge.moved_vertices = {{4, glm::vec3(0.0f, 0.0f, 0.9f), glm::vec3(0, 0, 1)}};
    const EncodedDeltaV2 m = round_trip(mesh, merge, e.next_triangle_id, e.next_vertex_id);
    EXPECT_EQ(m.stats.explicit_removed, 4u);
    EXPECT_EQ(m.stats.explicit_added, 2u);
    EXPECT_EQ(m.stats.moved, 1u);
    EXPECT_EQ(canonical(mesh), before);
    EXPECT_FALSE(mesh.vertex(6));
    EXPECT_NEAR(mesh.vertex(4)->position.z, 0.9f, 1e-3);
    if (const char* dir = std::getenv("ISOMESH_WRITE_FUZZ_SEEDS")) {  // tests/fuzz/frame_decoder
        std::ofstream(std::string(dir) + "/delta_v2_split.bin", std::ios::binary)
            .write(reinterpret_cast<const char*>(e.bytes.data()), e.bytes.size());
    }
}

/// An icosphere of `radius` held as a client decodes it on the octahedron's grid.
HeldMesh held_sphere(float radius) {
    const GridMath grid(samples::octahedron_grid());
    const samples::SampleMesh sphere = samples::icosphere(4, radius);
    DecodedFrame frame;
    frame.header.kind = FrameKind::keyframe;
    for (const Vertex& v : sphere.vertices) {
        frame.vertices.push_back({v.id, grid.dequantize(grid.quantize(v.position)),
                                  grid.decode_normal(grid.encode_normal(glm::dvec3(v.normal)))});
    }
    for (std::size_t t = 0; t < sphere.triangles.size(); ++t)
        frame.triangles.push_back({t, sphere.triangles[t].vertices});
    HeldMesh mesh;
    mesh.apply(frame);
    return mesh;
}

TEST(DeltaV2, moved_vertices_are_said_by_their_offset_along_the_normal) {
    // A growing sphere (a slider on its radius): every vertex moves along its normal.
    HeldMesh mesh = held_sphere(0.6f);
    const samples::SampleMesh target = samples::icosphere(4, 0.65f);
    DeltaV2Change change;
    change.moved_vertices = target.vertices;
    const EncodedDeltaV2 e = round_trip(mesh, change, 1'000'000, 100'000);
    ASSERT_EQ(e.stats.moved, target.vertices.size());
    // Each vertex lands exactly on its target's grid point, its normal on the target's code.
    const GridMath grid(samples::octahedron_grid());
    for (const Vertex& v : target.vertices) {
        const Vertex* held = mesh.vertex(v.id);
        ASSERT_TRUE(held);
        EXPECT_EQ(grid.recover(held->position), grid.quantize(v.position));
        EXPECT_EQ(grid.encode_normal(glm::dvec3(held->normal)),
                  grid.encode_normal(glm::dvec3(v.normal)));
    }
    // The offset is the same everywhere: a few bits a vertex, where residuals per axis of about
    // 0.05 / (2.0625 / 16383) = 400 grid steps took over 10 bits each.
    EXPECT_LT(e.stats.moved_bits / static_cast<double>(e.stats.moved), 6.0);
}

TEST(DeltaV2, a_moved_vertex_offset_beyond_the_grid_is_refused) {
    HeldMesh mesh = samples::octahedron();
    const QuantizationGrid grid = samples::octahedron_grid();
    // Hand-made body: no splits, removals, loose vertices or triangles; one moved vertex (id 0),
    // offset 2^16 (beyond 2^(B+1) = 2^15), then zero residuals.
    RangeEncoder coder;
    IntModel count, gap, offset, position, normal;
    for (int i = 0; i < 4; ++i) coder.uint(count, 0);
    coder.uint(count, 1);
    coder.uint(gap, 0);
    coder.sint(offset, std::int64_t{1} << 16);
    for (int axis = 0; axis < 3; ++axis) coder.sint(position, 0);
    for (int k = 0; k < 2; ++k) coder.sint(normal, 0);
    auto encoded = encode_delta_v2(delta_info(1), mesh, {}, 8, 6, grid);
    ASSERT_TRUE(encoded.ok());
    std::vector<std::uint8_t> bytes(encoded.value().bytes.begin(),
                                    encoded.value().bytes.begin() + kDeltaV2HeaderBytes);
    const std::vector<std::uint8_t> body = coder.finish();
    bytes.insert(bytes.end(), body.begin(), body.end());
    auto decoded = decode_delta_v2(bytes, mesh, grid);
    ASSERT_FALSE(decoded.ok());
    EXPECT_EQ(decoded.error().code, ErrorCode::bad_frame);
    EXPECT_NE(decoded.error().message.find("offset"), std::string::npos) << decoded.error().message;
}

TEST(DeltaV2, a_delta_that_does_not_fit_the_held_mesh_is_refused) {
    HeldMesh mesh = samples::octahedron();
    DeltaV2Change change;
    change.removed = {0, 4};
    change.new_vertices = {{6, glm::vec3(0.7f, 0.7f, 0.0f), glm::vec3(1, 1, 0)}};
    change.added = {{{0, 6, 4}}, {{6, 2, 4}}, {{2, 6, 5}}, {{6, 0, 5}}};
    const QuantizationGrid grid = samples::octahedron_grid();
    auto encoded = encode_delta_v2(delta_info(1), mesh, change, 8, 6, grid);
    ASSERT_TRUE(encoded.ok());
    const HeldMesh empty;
    auto decoded = decode_delta_v2(encoded.value().bytes, empty, grid);
    ASSERT_FALSE(decoded.ok());
    EXPECT_EQ(decoded.error().code, ErrorCode::bad_frame);
    auto bytes = encoded.value().bytes;
    bytes.resize(kDeltaV2HeaderBytes + 2);
    EXPECT_FALSE(decode_delta_v2(bytes, mesh, grid).ok());
    DeltaV2Change unknown;
    unknown.removed = {99};
    EXPECT_EQ(encode_delta_v2(delta_info(1), mesh, unknown, 8, 6, grid).error().code,
              ErrorCode::bad_field);
}

}  // namespace
}  // namespace isomesh::protocol
