// PROTOCOL.md's byte-by-byte example frame must be what the decoder reads.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "protocol/frame.h"

namespace isomesh::protocol {
namespace {

std::string read_document() {
    std::ifstream in(std::string(ISOMESH_SOURCE_DIR) + "/protocol/PROTOCOL.md");
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
}

/// The hex bytes between the example-frame markers.
std::vector<std::uint8_t> example_frame(const std::string& document) {
    const auto begin = document.find("<!-- example-frame -->");
    const auto end = document.find("<!-- /example-frame -->");
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

TEST(ProtocolDocument, header_size_matches) {
    EXPECT_NE(read_document().find("A binary frame is a 76-byte header"), std::string::npos);
    EXPECT_EQ(kFrameHeaderBytes, 76u);
}

}  // namespace
}  // namespace isomesh::protocol
