#include "protocol/frame.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "protocol/tools/sample_mesh.h"
#include "protocol/varint.h"

namespace isomesh::protocol {
namespace {

using Bytes = std::vector<std::uint8_t>;

MeshEncoding unit_encoding() {
    MeshEncoding encoding;
    encoding.grid = QuantizationGrid::for_box({-1, 1, -1, 1, -1, 1});
    return encoding;
}

FrameInfo delta_info(std::uint64_t sequence = 7) {
    return {FrameKind::delta, 0, samples::sample_session_id(), sequence, 1'700'000'000'000'123, 3};
}

FrameHeader sample_header() {
    FrameHeader h;
    h.kind = FrameKind::keyframe;
    h.flags = frame_flags::catch_up;
    h.session = samples::sample_session_id();
    h.sequence = 0x0102030405060708;
    h.timestamp_us = 1'700'000'000'000'001;
    h.base_triangle_id = 42;
    h.function_version = 9;
    h.triangle_count = 10;
    h.point_count = 8;
    h.triangle_ids_bytes = 10;
    h.mesh_bytes = 300;
    return h;
}

Bytes header_bytes(const FrameHeader& h) {
    Bytes out(kFrameHeaderBytes);
    write_frame_header(h, std::span<std::uint8_t, kFrameHeaderBytes>(out));
    return out;
}

/// Mutates one header field of a valid frame and expects decode_frame to fail with `code`.
void expect_rejected(Bytes frame, std::size_t offset, std::uint32_t value,
                     ErrorCode code = ErrorCode::bad_frame) {
    for (std::size_t i = 0; i < 4; ++i)
        frame[offset + i] = static_cast<std::uint8_t>(value >> (8 * i));
    auto decoded = decode_frame(frame);
    ASSERT_FALSE(decoded) << "offset " << offset << " value " << value;
    EXPECT_EQ(decoded.error().code, code) << decoded.error().message;
}

struct SampleDelta {
    samples::SampleMesh sphere;
    std::vector<Triangle> added;
    std::vector<std::uint64_t> removed;
    EncodedFrame frame;
};

SampleDelta sample_delta() {
    SampleDelta d;
    d.sphere = samples::icosphere(3);
    const auto chosen = samples::cap(d.sphere, {0, 1, 0}, 30);
    const auto split =
        samples::subdivide(d.sphere, chosen, static_cast<std::uint32_t>(d.sphere.vertices.size()));
    d.sphere.vertices.insert(d.sphere.vertices.end(), split.vertices.begin(), split.vertices.end());
    d.added = split.triangles;
    d.removed.assign(chosen.rbegin(), chosen.rend());  // unsorted on purpose
    auto frame =
        encode_delta(delta_info(), {d.removed, d.sphere.vertices, d.added, 5000}, unit_encoding());
    EXPECT_TRUE(frame);
    if (frame) d.frame = frame.value();
    return d;
}

TEST(FrameHeader, round_trip) {
    const FrameHeader h = sample_header();
    auto read = read_frame_header(header_bytes(h));
    ASSERT_TRUE(read) << read.error().message;
    EXPECT_EQ(read.value(), h);
}

TEST(FrameHeader, byte_layout_is_little_endian_as_documented) {
    const Bytes b = header_bytes(sample_header());
    EXPECT_EQ(std::string(b.begin(), b.begin() + 4), "ISOM");
    EXPECT_EQ(b[4], 1);                      // protocol version
    EXPECT_EQ(b[5], 1);                      // keyframe
    EXPECT_EQ(b[6], frame_flags::catch_up);  // flags, low byte first
    EXPECT_EQ(b[8 + 1], 0x11);               // session id bytes in order
    EXPECT_EQ(b[24], 0x08);                  // sequence, least significant first
    EXPECT_EQ(b[31], 0x01);
    EXPECT_EQ(b[40], 42);                // base triangle id
    EXPECT_EQ(b[48], 9);                 // function version
    EXPECT_EQ(b[56], 10);                // triangle count
    EXPECT_EQ(b[60], 8);                 // point count
    EXPECT_EQ(b[68], 10);                // explicit ids bytes
    EXPECT_EQ(b[72] | b[73] << 8, 300);  // mesh bytes
}

TEST(FrameHeader, rejects_invalid_headers) {
    const Bytes valid = header_bytes(sample_header());
    auto rejected = [](Bytes b, ErrorCode code = ErrorCode::bad_frame) {
        auto read = read_frame_header(b);
        return !read && read.error().code == code;
    };
    EXPECT_TRUE(rejected(Bytes(valid.begin(), valid.end() - 1)));
    Bytes b = valid;
    b[0] = 'X';
    EXPECT_TRUE(rejected(b));
    b = valid;
    b[4] = 3;
    EXPECT_TRUE(rejected(b, ErrorCode::unsupported_version));
    b = valid;
    b[5] = 3;
    EXPECT_TRUE(rejected(b));
    b = valid;
    b[52] = 1;  // a keyframe that removes a triangle
    EXPECT_TRUE(rejected(b));
    b = valid;
    b[48] = 0;  // function version 0
    EXPECT_TRUE(rejected(b));
    b = valid;
    std::fill(b.begin() + 72, b.begin() + 76, 0);  // triangles but no payload
    EXPECT_TRUE(rejected(b));
    b = valid;
    b[60] = 31;  // more points than 3 per triangle
    EXPECT_TRUE(rejected(b));
    b = valid;
    b[58] = 0x40;  // 2^22 + 10 triangles
    EXPECT_TRUE(rejected(b));
}

TEST(FrameHeader, rejects_implicit_ids_beyond_2_pow_53) {
    FrameHeader h = sample_header();
    h.triangle_ids_bytes = 0;
    h.base_triangle_id = kMaxTriangleId - 8;  // 10 triangles: the last id would be max + 1
    EXPECT_FALSE(read_frame_header(header_bytes(h)));
    h.base_triangle_id = kMaxTriangleId - 9;
    EXPECT_TRUE(read_frame_header(header_bytes(h)));
}

TEST(Frame, delta_round_trip_numbers_triangles_by_decoded_order) {
    const SampleDelta d = sample_delta();
    auto decoded = decode_frame(d.frame.bytes);
    ASSERT_TRUE(decoded) << decoded.error().message;
    const DecodedFrame& f = decoded.value();
    EXPECT_EQ(f.header.kind, FrameKind::delta);
    EXPECT_EQ(f.header.sequence, 7u);
    EXPECT_EQ(f.header.function_version, 3u);
    EXPECT_EQ(f.header.session, samples::sample_session_id());
    std::vector<std::uint64_t> sorted_removed = d.removed;
    std::sort(sorted_removed.begin(), sorted_removed.end());
    EXPECT_EQ(f.removed, sorted_removed);
    ASSERT_EQ(f.triangles.size(), d.added.size());
    for (std::size_t i = 0; i < f.triangles.size(); ++i) EXPECT_EQ(f.triangles[i].id, 5000 + i);
    for (std::size_t i = 0; i < d.added.size(); ++i) {
        const std::uint64_t id = d.frame.triangle_ids[i];
        ASSERT_GE(id, 5000u);
        const FrameTriangle& t = f.triangles[id - 5000];
        EXPECT_EQ(canonical_rotation(t.vertices), canonical_rotation(d.added[i].vertices));
    }
}

TEST(Frame, keyframe_keeps_given_ids) {
    const auto sphere = samples::icosphere(2);
    std::vector<std::uint64_t> ids(sphere.triangles.size());
    for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = 3 * i + (i % 2 ? 1000 : 0);
    FrameInfo info = delta_info(11);
    info.kind = FrameKind::keyframe;
    auto frame = encode_keyframe(info, sphere.vertices, sphere.triangles, ids, unit_encoding());
    ASSERT_TRUE(frame) << frame.error().message;
    auto decoded = decode_frame(frame.value().bytes);
    ASSERT_TRUE(decoded) << decoded.error().message;
    EXPECT_GT(decoded.value().header.triangle_ids_bytes, 0u);
    std::vector<FrameTriangle> expected, actual;
    for (std::size_t i = 0; i < ids.size(); ++i) {
        expected.push_back({ids[i], canonical_rotation(sphere.triangles[i].vertices)});
    }
    for (const FrameTriangle& t : decoded.value().triangles) {
        actual.push_back({t.id, canonical_rotation(t.vertices)});
    }
    auto by_id = [](const FrameTriangle& a, const FrameTriangle& b) { return a.id < b.id; };
    std::sort(expected.begin(), expected.end(), by_id);
    std::sort(actual.begin(), actual.end(), by_id);
    EXPECT_EQ(actual, expected);
}

TEST(Frame, keyframe_with_ids_consecutive_in_decoded_order_needs_no_id_section) {
    const auto sphere = samples::icosphere(1);
    std::vector<std::uint64_t> ids(sphere.triangles.size());
    FrameInfo info = delta_info(0);
    info.kind = FrameKind::keyframe;
    // First pass learns the decoded order; then number triangles 100, 101, ... in that order.
    auto first = encode_keyframe(info, sphere.vertices, sphere.triangles,
                                 std::vector<std::uint64_t>(ids.size(), 0), unit_encoding());
    ASSERT_FALSE(first);  // ids must be distinct
    for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = i;
    auto probe = encode_keyframe(info, sphere.vertices, sphere.triangles, ids, unit_encoding());
    ASSERT_TRUE(probe);
    auto probe_decoded = decode_frame(probe.value().bytes);
    ASSERT_TRUE(probe_decoded);
    for (std::size_t k = 0; k < ids.size(); ++k) {
        const auto& t = probe_decoded.value().triangles[k];
        ids[t.id] = 100 + k;  // triangle t.id sits at decoded position k
    }
    auto frame = encode_keyframe(info, sphere.vertices, sphere.triangles, ids, unit_encoding());
    ASSERT_TRUE(frame);
    auto decoded = decode_frame(frame.value().bytes);
    ASSERT_TRUE(decoded);
    EXPECT_EQ(decoded.value().header.triangle_ids_bytes, 0u);
    EXPECT_EQ(decoded.value().header.base_triangle_id, 100u);
}

TEST(Frame, numbered_keyframe_gives_ids_in_decoded_order_and_has_no_id_section) {
    const auto sphere = samples::icosphere(2);
    FrameInfo info = delta_info(0);
    info.kind = FrameKind::keyframe;
    info.protocol_version = 2;
    auto frame =
        encode_keyframe_numbered(info, sphere.vertices, sphere.triangles, 500, unit_encoding());
    ASSERT_TRUE(frame);
    auto decoded = decode_frame(frame.value().bytes);
    ASSERT_TRUE(decoded);
    EXPECT_EQ(decoded.value().header.triangle_ids_bytes, 0u);
    EXPECT_EQ(decoded.value().header.base_triangle_id, 500u);
    // Each input triangle's id is where the decoder finds it (corners up to rotation).
    const auto& ids = frame.value().triangle_ids;
    ASSERT_EQ(ids.size(), sphere.triangles.size());
    for (std::size_t i = 0; i < ids.size(); ++i) {
        const FrameTriangle& t = decoded.value().triangles.at(ids[i] - 500);
        EXPECT_EQ(t.id, ids[i]);
        EXPECT_EQ(canonical_rotation(t.vertices), canonical_rotation(sphere.triangles[i].vertices));
    }
}

TEST(Frame, empty_keyframe_and_removal_only_delta) {
    FrameInfo info = delta_info(0);
    info.kind = FrameKind::keyframe;
    auto empty = encode_keyframe(info, {}, {}, {}, unit_encoding());
    ASSERT_TRUE(empty);
    EXPECT_EQ(empty.value().bytes.size(), kFrameHeaderBytes);
    auto decoded = decode_frame(empty.value().bytes);
    ASSERT_TRUE(decoded);
    EXPECT_TRUE(decoded.value().triangles.empty());

    const std::vector<std::uint64_t> removed = {9, 3, 7};
    auto removal = encode_delta(delta_info(), {removed, {}, {}, 0}, unit_encoding());
    ASSERT_TRUE(removal);
    auto removal_decoded = decode_frame(removal.value().bytes);
    ASSERT_TRUE(removal_decoded);
    EXPECT_EQ(removal_decoded.value().removed, (std::vector<std::uint64_t>{3, 7, 9}));
    EXPECT_EQ(removal.value().bytes.size(), kFrameHeaderBytes + 3);
}

TEST(Frame, encode_rejects_invalid_input) {
    const auto sphere = samples::icosphere(1);
    const std::vector<std::uint64_t> repeated = {4, 4};
    EXPECT_FALSE(encode_delta(delta_info(), {repeated, {}, {}, 0}, unit_encoding()));
    const std::vector<std::uint64_t> too_big = {kMaxTriangleId + 1};
    EXPECT_FALSE(encode_delta(delta_info(), {too_big, {}, {}, 0}, unit_encoding()));
    EXPECT_FALSE(encode_delta(delta_info(),
                              {{}, sphere.vertices, sphere.triangles, kMaxTriangleId - 2},
                              unit_encoding()));
    FrameInfo info = delta_info();
    info.kind = FrameKind::keyframe;
    EXPECT_FALSE(encode_keyframe(info, sphere.vertices, sphere.triangles,
                                 std::vector<std::uint64_t>{1, 2}, unit_encoding()));
}

TEST(Frame, decode_rejects_every_truncation) {
    const SampleDelta d = sample_delta();
    for (std::size_t length = 0; length < d.frame.bytes.size(); ++length) {
        auto decoded = decode_frame(std::span(d.frame.bytes.data(), length));
        ASSERT_FALSE(decoded) << "length " << length;
    }
    Bytes longer = d.frame.bytes;
    longer.push_back(0);
    EXPECT_FALSE(decode_frame(longer));
}

TEST(Frame, decode_rejects_inconsistent_headers) {
    const Bytes frame = sample_delta().frame.bytes;
    auto header = read_frame_header(frame);
    ASSERT_TRUE(header);
    const FrameHeader& h = header.value();
    expect_rejected(frame, 52, h.removed_count + 1);   // more removed ids than coded
    expect_rejected(frame, 52, h.removed_count - 1);   // fewer: bytes left over
    expect_rejected(frame, 56, h.triangle_count + 1);  // Draco holds fewer triangles
    expect_rejected(frame, 60, h.point_count - 1);     // Draco holds more points
    expect_rejected(frame, 64, h.removed_bytes + 1);   // sections no longer add up
    expect_rejected(frame, 72, h.mesh_bytes - 1);
}

TEST(Frame, decode_rejects_repeated_explicit_ids) {
    const auto sphere = samples::icosphere(0);
    FrameInfo info = delta_info(0);
    info.kind = FrameKind::keyframe;
    std::vector<std::uint64_t> ids(sphere.triangles.size());
    for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = 10 * i;
    auto frame = encode_keyframe(info, sphere.vertices, sphere.triangles, ids, unit_encoding());
    ASSERT_TRUE(frame);
    Bytes bytes = frame.value().bytes;
    auto h = read_frame_header(bytes).value();
    // Rewrite the id section with every id equal (all steps zero but the first).
    std::vector<std::uint64_t> same(h.triangle_count, 10);
    const Bytes section = encode_id_sequence(same, 0);
    ASSERT_LE(section.size(), h.triangle_ids_bytes);
    Bytes forged(bytes.begin(), bytes.begin() + kFrameHeaderBytes);
    forged.insert(forged.end(), section.begin(), section.end());
    forged.insert(forged.end(), bytes.end() - h.mesh_bytes, bytes.end());
    h.triangle_ids_bytes = static_cast<std::uint32_t>(section.size());
    write_frame_header(
        h, std::span<std::uint8_t, kFrameHeaderBytes>(forged.data(), kFrameHeaderBytes));
    auto decoded = decode_frame(forged);
    ASSERT_FALSE(decoded);
    EXPECT_NE(decoded.error().message.find("repeat"), std::string::npos);
}

TEST(Frame, decode_survives_every_single_byte_corruption) {
    // Flipping any byte gives an error or a frame that decodes consistently; never a crash.
    const Bytes frame = sample_delta().frame.bytes;
    int rejected = 0;
    for (std::size_t i = 0; i < frame.size(); ++i) {
        for (std::uint8_t mask : {0x01, 0x80, 0xff}) {
            Bytes corrupt = frame;
            corrupt[i] ^= mask;
            auto decoded = decode_frame(corrupt);
            if (!decoded) {
                ++rejected;
                continue;
            }
            EXPECT_EQ(decoded.value().triangles.size(), decoded.value().header.triangle_count);
        }
    }
    EXPECT_GT(rejected, 0);
}

}  // namespace
}  // namespace isomesh::protocol
