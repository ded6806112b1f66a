#include "protocol/mesh_codec.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <unordered_map>

#include <glm/geometric.hpp>

#include "protocol/tools/sample_mesh.h"

namespace isomesh::protocol {
namespace {

using samples::icosphere;

MeshEncoding sphere_encoding(int bits = 14) {
    MeshEncoding encoding;
    encoding.grid = QuantizationGrid::for_box({-1, 1, -1, 1, -1, 1}, bits);
    return encoding;
}

std::unordered_map<std::uint32_t, Vertex> by_id(const std::vector<Vertex>& vertices) {
    std::unordered_map<std::uint32_t, Vertex> out;
    for (const Vertex& v : vertices) out[v.id] = v;
    return out;
}

std::uint32_t float_bits(float x) {
    std::uint32_t bits = 0;
    std::memcpy(&bits, &x, sizeof bits);
    return bits;
}

/// True when b lists a's vertices in the same cyclic order.
bool same_rotation(const Triangle& a, const Triangle& b) {
    for (int shift = 0; shift < 3; ++shift) {
        if (a.vertices[0] == b.vertices[shift] && a.vertices[1] == b.vertices[(shift + 1) % 3] &&
            a.vertices[2] == b.vertices[(shift + 2) % 3]) {
            return true;
        }
    }
    return false;
}

TEST(MeshCodec, round_trip_keeps_ids_and_quantizes_positions) {
    const auto sphere = icosphere(3, 1.0f, 100);
    const MeshEncoding encoding = sphere_encoding();
    auto encoded = encode_mesh(sphere.vertices, sphere.triangles, encoding);
    ASSERT_TRUE(encoded) << encoded.error().message;
    auto decoded = decode_mesh(encoded.value().bytes);
    ASSERT_TRUE(decoded) << decoded.error().message;

    ASSERT_EQ(decoded.value().vertices.size(), sphere.vertices.size());
    const auto original = by_id(sphere.vertices);
    const float step = encoding.grid.range / float((1 << encoding.grid.position_bits) - 1);
    for (const Vertex& v : decoded.value().vertices) {
        auto it = original.find(v.id);
        ASSERT_NE(it, original.end()) << "unknown global id " << v.id;
        for (int axis = 0; axis < 3; ++axis) {
            EXPECT_LE(std::abs(v.position[axis] - it->second.position[axis]), 0.5f * step + 1e-6f);
        }
        // 10-bit octahedral normals: well under a degree of error.
        EXPECT_GT(glm::dot(v.normal, it->second.normal), std::cos(3.14159265f / 180.0f));
    }
}

TEST(MeshCodec, triangle_order_is_the_reported_decoded_index) {
    const auto sphere = icosphere(3);
    auto encoded = encode_mesh(sphere.vertices, sphere.triangles, sphere_encoding());
    ASSERT_TRUE(encoded);
    auto decoded = decode_mesh(encoded.value().bytes);
    ASSERT_TRUE(decoded);
    const auto& index = encoded.value().decoded_index;
    ASSERT_EQ(index.size(), sphere.triangles.size());
    std::vector<bool> used(index.size(), false);
    bool reordered = false;
    for (std::size_t i = 0; i < index.size(); ++i) {
        ASSERT_LT(index[i], decoded.value().triangles.size());
        EXPECT_FALSE(used[index[i]]) << "two triangles map to decoded index " << index[i];
        used[index[i]] = true;
        reordered = reordered || index[i] != i;
        EXPECT_TRUE(same_rotation(sphere.triangles[i], decoded.value().triangles[index[i]]))
            << "triangle " << i;
    }
    EXPECT_TRUE(reordered) << "edgebreaker is expected to reorder faces; the test would be vacuous";
}

TEST(MeshCodec, shared_vertex_decodes_to_identical_bits_in_two_payloads) {
    const auto sphere = icosphere(4);
    const auto north = samples::cap(sphere, {0, 0, 1}, 300);
    const auto tilted = samples::cap(sphere, {0.3f, 0.2f, 1}, 500);
    const MeshEncoding encoding = sphere_encoding();
    auto first = encode_mesh(sphere.vertices, samples::pick(sphere, north), encoding);
    auto second = encode_mesh(sphere.vertices, samples::pick(sphere, tilted), encoding);
    ASSERT_TRUE(first && second);
    auto a = decode_mesh(first.value().bytes);
    auto b = decode_mesh(second.value().bytes);
    ASSERT_TRUE(a && b);
    const auto in_a = by_id(a.value().vertices);
    int shared = 0;
    for (const Vertex& v : b.value().vertices) {
        auto it = in_a.find(v.id);
        if (it == in_a.end()) continue;
        ++shared;
        for (int axis = 0; axis < 3; ++axis) {
            EXPECT_EQ(float_bits(v.position[axis]), float_bits(it->second.position[axis]))
                << "vertex " << v.id << " axis " << axis;
        }
    }
    EXPECT_GT(shared, 50);
}

TEST(MeshCodec, encode_rotation_in_input_is_matched) {
    // The same triangles given with their corners rotated still map one to one.
    auto sphere = icosphere(2);
    for (std::size_t i = 0; i < sphere.triangles.size(); i += 3) {
        auto& v = sphere.triangles[i].vertices;
        std::rotate(v.begin(), v.begin() + 1 + i % 2, v.end());
    }
    auto encoded = encode_mesh(sphere.vertices, sphere.triangles, sphere_encoding());
    ASSERT_TRUE(encoded);
    auto decoded = decode_mesh(encoded.value().bytes);
    ASSERT_TRUE(decoded);
    for (std::size_t i = 0; i < sphere.triangles.size(); ++i) {
        EXPECT_TRUE(same_rotation(sphere.triangles[i],
                                  decoded.value().triangles[encoded.value().decoded_index[i]]));
    }
}

TEST(MeshCodec, non_manifold_and_disconnected_input_round_trips) {
    // Two triangles sharing one vertex only (a bow tie), plus a detached one.
    const std::vector<Vertex> vertices = {
        {1, {0, 0, 0}, {0, 0, 1}},          {2, {1, 0, 0}, {0, 0, 1}},
        {3, {0, 1, 0}, {0, 0, 1}},          {4, {-1, 0, 0}, {0, 0, 1}},
        {5, {0, -1, 0}, {0, 0, 1}},         {6, {0.5f, 0.5f, 0.5f}, {1, 0, 0}},
        {7, {0.6f, 0.5f, 0.5f}, {1, 0, 0}}, {8, {0.5f, 0.6f, 0.5f}, {1, 0, 0}}};
    const std::vector<Triangle> triangles = {{{1, 2, 3}}, {{1, 4, 5}}, {{6, 7, 8}}};
    auto encoded = encode_mesh(vertices, triangles, sphere_encoding());
    ASSERT_TRUE(encoded) << encoded.error().message;
    auto decoded = decode_mesh(encoded.value().bytes);
    ASSERT_TRUE(decoded);
    EXPECT_EQ(decoded.value().vertices.size(), 8u);
    EXPECT_GE(encoded.value().point_count, 8u);
    for (std::size_t i = 0; i < triangles.size(); ++i) {
        EXPECT_TRUE(same_rotation(triangles[i],
                                  decoded.value().triangles[encoded.value().decoded_index[i]]));
    }
}

TEST(MeshCodec, positions_outside_the_grid_are_clamped) {
    const std::vector<Vertex> vertices = {
        {0, {5, 0, 0}, {1, 0, 0}}, {1, {0, 1, 0}, {0, 1, 0}}, {2, {0, 0, 1}, {0, 0, 1}}};
    const std::vector<Triangle> triangles = {{{0, 1, 2}}};
    const MeshEncoding encoding = sphere_encoding();
    auto encoded = encode_mesh(vertices, triangles, encoding);
    ASSERT_TRUE(encoded);
    auto decoded = decode_mesh(encoded.value().bytes);
    ASSERT_TRUE(decoded);
    const auto out = by_id(decoded.value().vertices);
    EXPECT_NEAR(out.at(0).position.x, encoding.grid.origin.x + encoding.grid.range, 1e-4f);
}

TEST(MeshCodec, zero_normal_decodes_as_x_axis) {
    const std::vector<Vertex> vertices = {
        {0, {0, 0, 0}, {0, 0, 0}}, {1, {0, 1, 0}, {0, 1, 0}}, {2, {0, 0, 1}, {0, 0, 1}}};
    auto encoded = encode_mesh(vertices, std::vector<Triangle>{{{0, 1, 2}}}, sphere_encoding());
    ASSERT_TRUE(encoded);
    auto decoded = decode_mesh(encoded.value().bytes);
    ASSERT_TRUE(decoded);
    EXPECT_NEAR(by_id(decoded.value().vertices).at(0).normal.x, 1.0f, 1e-3f);
}

TEST(MeshCodec, encode_rejects_bad_input) {
    const std::vector<Vertex> vertices = {
        {0, {0, 0, 0}, {0, 0, 1}}, {1, {1, 0, 0}, {0, 0, 1}}, {2, {0, 1, 0}, {0, 0, 1}}};
    const MeshEncoding encoding = sphere_encoding();
    auto expect_bad_field = [&](std::span<const Vertex> v, std::vector<Triangle> t) {
        auto encoded = encode_mesh(v, t, encoding);
        ASSERT_FALSE(encoded);
        EXPECT_EQ(encoded.error().code, ErrorCode::bad_field) << encoded.error().message;
    };
    expect_bad_field(vertices, {});
    expect_bad_field(vertices, {{{0, 1, 9}}});
    expect_bad_field(vertices, {{{0, 1, 1}}});
    std::vector<Vertex> repeated = vertices;
    repeated.push_back(vertices[0]);
    expect_bad_field(repeated, {{{0, 1, 2}}});
    std::vector<Vertex> nan = vertices;
    nan[1].position.y = std::nanf("");
    expect_bad_field(nan, {{{0, 1, 2}}});
}

TEST(MeshCodec, decode_rejects_garbage_and_truncation) {
    const auto sphere = icosphere(2);
    auto encoded = encode_mesh(sphere.vertices, sphere.triangles, sphere_encoding());
    ASSERT_TRUE(encoded);
    const auto& bytes = encoded.value().bytes;
    for (std::size_t length :
         {std::size_t{0}, std::size_t{5}, bytes.size() / 2, bytes.size() - 1}) {
        auto decoded = decode_mesh(std::span(bytes.data(), length));
        ASSERT_FALSE(decoded) << "length " << length;
        EXPECT_EQ(decoded.error().code, ErrorCode::bad_frame);
    }
    const std::vector<std::uint8_t> garbage(200, 0xab);
    EXPECT_FALSE(decode_mesh(garbage));
}

TEST(MeshCodec, grid_for_box_is_a_cube_with_margin) {
    const auto grid = QuantizationGrid::for_box({-2, 2, -1, 1, 0, 3}, 16);
    EXPECT_FLOAT_EQ(grid.range, 4.0f * (1.0f + 2.0f / 64.0f));
    EXPECT_FLOAT_EQ(grid.origin.x + grid.range / 2, 0.0f);
    EXPECT_FLOAT_EQ(grid.origin.z + grid.range / 2, 1.5f);
    EXPECT_LT(grid.origin.x, -2.0f);
    EXPECT_EQ(grid.position_bits, 16);
}

}  // namespace
}  // namespace isomesh::protocol
