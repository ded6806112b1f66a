// Invalid close codes are rewritten before Beast sees them, whatever the reads' sizes (14.8).
#include "server/close_code_filter.h"

#include <gtest/gtest.h>

#include <vector>

namespace isomesh::server {
namespace {

using Bytes = std::vector<std::uint8_t>;

/// A masked client frame with `opcode` and `payload`.
Bytes client_frame(std::uint8_t opcode, const Bytes& payload,
                   std::array<std::uint8_t, 4> key = {0x11, 0x22, 0x33, 0x44}) {
    Bytes out = {static_cast<std::uint8_t>(0x80 | opcode)};
    if (payload.size() < 126) {
        out.push_back(static_cast<std::uint8_t>(0x80 | payload.size()));
    } else {
        out.push_back(0x80 | 126);
        out.push_back(static_cast<std::uint8_t>(payload.size() >> 8));
        out.push_back(static_cast<std::uint8_t>(payload.size() & 0xFF));
    }
    out.insert(out.end(), key.begin(), key.end());
    for (std::size_t i = 0; i < payload.size(); ++i) out.push_back(payload[i] ^ key[i % 4]);
    return out;
}

Bytes close_payload(std::uint16_t code) {
    return {static_cast<std::uint8_t>(code >> 8), static_cast<std::uint8_t>(code & 0xFF), 'b', 'y'};
}

/// The close code of the close frame at `close_at` after filtering `stream` in reads of `piece`
/// bytes, as FilteredStream reads: a byte held back is offered again with the next read.
std::uint16_t filtered_code(Bytes stream, std::size_t close_at, std::size_t piece) {
    CloseCodeFilter filter;
    std::size_t released = 0, held = 0;
    while (released < stream.size()) {
        const std::size_t end = std::min(stream.size(), released + held + piece);
        const std::size_t offered = end - released;
        const std::size_t n = filter.filter(std::span(stream).subspan(released, offered));
        released += n;
        held = offered - n;
        if (n == 0 && end == stream.size()) break;
    }
    const std::uint8_t* key = &stream[close_at + 2];
    return static_cast<std::uint16_t>((stream[close_at + 6] ^ key[0]) << 8 |
                                      (stream[close_at + 7] ^ key[1]));
}

TEST(CloseCodeFilter, valid_close_codes_follow_rfc_6455) {
    for (std::uint16_t code : {1000, 1001, 1002, 1003, 1007, 1011, 1014, 3000, 4999})
        EXPECT_TRUE(valid_close_code(code)) << code;
    for (std::uint16_t code : {0, 999, 1004, 1005, 1006, 1015, 1016, 2999, 5000, 65535})
        EXPECT_FALSE(valid_close_code(code)) << code;
}

TEST(CloseCodeFilter, rewrites_an_invalid_code_to_1005_in_reads_of_any_size) {
    const Bytes text = client_frame(0x1, Bytes(300, 'x'));
    for (std::size_t piece : {1u, 2u, 3u, 5u, 7u, 64u, 4096u}) {
        Bytes stream = text;
        const std::size_t close_at = stream.size();
        const Bytes close = client_frame(0x8, close_payload(5000));
        stream.insert(stream.end(), close.begin(), close.end());
        EXPECT_EQ(filtered_code(stream, close_at, piece), 1005) << piece;
    }
}

TEST(CloseCodeFilter, leaves_valid_codes_and_other_frames_alone) {
    Bytes stream = client_frame(0x1, Bytes(200, 0x88));  // 16-bit extended length
    const std::size_t close_at = stream.size();
    const Bytes close = client_frame(0x8, close_payload(4000));
    stream.insert(stream.end(), close.begin(), close.end());
    const Bytes before = stream;
    EXPECT_EQ(filtered_code(stream, close_at, 3), 4000);
    CloseCodeFilter filter;
    Bytes copy = before;
    EXPECT_EQ(filter.filter(copy), copy.size());
    EXPECT_EQ(copy, before);
}

TEST(CloseCodeFilter, holds_back_the_first_byte_of_a_code_until_the_second_comes) {
    Bytes stream = client_frame(0x8, close_payload(6000));
    CloseCodeFilter filter;
    EXPECT_EQ(filter.filter(std::span(stream).first(7)), 6u);  // header (6 bytes) only
    EXPECT_EQ(filter.filter(std::span(stream).subspan(6)), stream.size() - 6);
    EXPECT_EQ((stream[6] ^ 0x11) << 8 | (stream[7] ^ 0x22), 1005);
}

}  // namespace
}  // namespace isomesh::server
