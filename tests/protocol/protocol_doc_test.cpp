// PROTOCOL.md's byte-by-byte example frame must be what the decoder reads.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "protocol/delta_v2.h"
#include "protocol/delta_v2_geometry.h"
#include "protocol/frame.h"
#include "protocol/tools/octahedron.h"

namespace isomesh::protocol {
namespace {

std::string read_document() {
    std::ifstream in(std::string(ISOMESH_SOURCE_DIR) + "/protocol/PROTOCOL.md");
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
}

/// The hex bytes between the markers <!-- NAME --> and <!-- /NAME -->.
std::vector<std::uint8_t> example_frame(const std::string& document,
                                        const std::string& name = "example-frame") {
    const auto begin = document.find("<!-- " + name + " -->");
    const auto end = document.find("<!-- /" + name + " -->");
    std::vector<std::uint8_t> bytes;
    if (begin == std::string::npos || end == std::string::npos) return bytes;
    std::istringstream block(document.substr(begin, end - begin));
    std::string token;
    while (block >> token) {
        if (token.size() == 2 && std::isxdigit(token[0]) && std::isxdigit(token[1])) {
            bytes.push_back(static_cast<std::uint8_t>(std::stoul(token, nullptr, 16)));
        }
    }
    return bytes;
}

TEST(ProtocolDocument, example_frame_decodes_as_described) {
    const auto bytes = example_frame(read_document());
    ASSERT_EQ(bytes.size(), 82u);
    auto frame = decode_frame(bytes);
    ASSERT_TRUE(frame) << frame.error().message;
    const FrameHeader& h = frame.value().header;
    EXPECT_EQ(h.kind, FrameKind::delta);
    EXPECT_EQ(h.flags, frame_flags::converged);
    EXPECT_EQ(h.session.to_hex(), "00112233445566778899aabbccddeeff");
    EXPECT_EQ(h.sequence, 5u);
    EXPECT_EQ(h.timestamp_us, 1'700'000'000'080'000u);
    EXPECT_EQ(h.function_version, 2u);
    EXPECT_EQ(frame.value().removed, (std::vector<std::uint64_t>{1021, 1035, 100318}));
    EXPECT_TRUE(frame.value().triangles.empty());
}

TEST(ProtocolDocument, version_2_example_delta_decodes_as_described) {
    const auto bytes = example_frame(read_document(), "example-frame-v2");
    ASSERT_EQ(bytes.size(), 68u);
    const HeldMesh octahedron = samples::octahedron();
    auto frame = decode_delta_v2(bytes, octahedron, samples::octahedron_grid());
    ASSERT_TRUE(frame) << frame.error().message;
    EXPECT_EQ(frame.value().header.sequence, 1u);
    EXPECT_EQ(frame.value().header.base_vertex_id, 6u);
    EXPECT_EQ(frame.value().removed, (std::vector<std::uint64_t>{0, 4}));
    const std::vector<FrameTriangle> added = {
        {8, {0, 6, 4}}, {9, {6, 2, 4}}, {10, {2, 6, 5}}, {11, {6, 0, 5}}};
    EXPECT_EQ(frame.value().triangles, added);
    const GridMath grid(samples::octahedron_grid());
    for (const Vertex& v : frame.value().vertices) {
        if (v.id == 6) {
            EXPECT_EQ(grid.recover(v.position), (GridPoint{13752, 13752, 8192}));
        }
    }
}

TEST(ProtocolDocument, version_2_example_move_decodes_as_described) {
    const auto bytes = example_frame(read_document(), "example-frame-v2-move");
    ASSERT_EQ(bytes.size(), 68u);
    const HeldMesh octahedron = samples::octahedron();
    auto frame = decode_delta_v2(bytes, octahedron, samples::octahedron_grid());
    ASSERT_TRUE(frame) << frame.error().message;
    EXPECT_TRUE(frame.value().removed.empty());
    EXPECT_TRUE(frame.value().triangles.empty());
    ASSERT_EQ(frame.value().vertices.size(), 6u);
    const GridMath grid(samples::octahedron_grid());
    for (const Vertex& v : frame.value().vertices) {
        const Vertex& held = *octahedron.vertex(v.id);
        // From grid point 16135 (+1) to 16373 (+1.03), or from 248 (-1) to 10 (-1.03).
        for (int axis = 0; axis < 3; ++axis) {
            const std::int64_t before = grid.recover(held.position)[axis];
            const std::int64_t after = grid.recover(v.position)[axis];
            EXPECT_EQ(after, before == 16135 ? 16373 : before == 248 ? 10 : before) << v.id;
        }
        EXPECT_EQ(v.normal, held.normal);
    }
}

TEST(ProtocolDocument, header_size_matches) {
    EXPECT_NE(read_document().find("A binary frame is a 76-byte header"), std::string::npos);
    EXPECT_EQ(kFrameHeaderBytes, 76u);
}

}  // namespace
}  // namespace isomesh::protocol
