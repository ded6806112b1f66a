#include "protocol/varint.h"

#include <gtest/gtest.h>

#include <limits>

namespace isomesh::protocol {
namespace {

using Bytes = std::vector<std::uint8_t>;

TEST(Varint, known_encodings) {
    auto encode = [](std::uint64_t value) {
        Bytes out;
        append_varint(out, value);
        return out;
    };
    EXPECT_EQ(encode(0), (Bytes{0x00}));
    EXPECT_EQ(encode(127), (Bytes{0x7f}));
    EXPECT_EQ(encode(128), (Bytes{0x80, 0x01}));
    EXPECT_EQ(encode(300), (Bytes{0xac, 0x02}));
    EXPECT_EQ(encode(std::numeric_limits<std::uint64_t>::max()).size(), 10u);
}

TEST(Varint, read_round_trips_extremes) {
    for (std::uint64_t value :
         {std::uint64_t{0}, std::uint64_t{1}, std::uint64_t{16383}, std::uint64_t{16384},
          std::uint64_t{1} << 53, std::numeric_limits<std::uint64_t>::max()}) {
        Bytes bytes;
        append_varint(bytes, value);
        std::size_t offset = 0;
        auto read = read_varint(bytes, offset);
        ASSERT_TRUE(read);
        EXPECT_EQ(read.value(), value);
        EXPECT_EQ(offset, bytes.size());
    }
}

TEST(Varint, read_rejects_malformed) {
    auto fails = [](Bytes bytes) {
        std::size_t offset = 0;
        auto read = read_varint(bytes, offset);
        return !read && read.error().code == ErrorCode::bad_frame && offset == 0;
    };
    EXPECT_TRUE(fails({}));
    EXPECT_TRUE(fails({0x80}));        // truncated
    EXPECT_TRUE(fails({0x80, 0x00}));  // not shortest
    Bytes wide(9, 0xff);
    wide.push_back(0x02);
    EXPECT_TRUE(fails(wide));             // 65 bits
    EXPECT_TRUE(fails(Bytes(11, 0x80)));  // too long
}

TEST(Varint, sorted_ids_round_trip_as_differences) {
    const std::vector<std::uint64_t> ids = {
        0, 1, 2, 130, 131, 1'000'000, (std::uint64_t{1} << 53) - 1};
    const Bytes bytes = encode_sorted_ids(ids);
    // 0, 1, 1, 128 (2 bytes), 1, 999869 (3 bytes), then a large step.
    EXPECT_EQ(bytes[0], 0);
    EXPECT_EQ(bytes[1], 1);
    EXPECT_EQ(bytes[3], 0x80);
    auto decoded = decode_sorted_ids(bytes, ids.size(), (std::uint64_t{1} << 53) - 1);
    ASSERT_TRUE(decoded);
    EXPECT_EQ(decoded.value(), ids);
}

TEST(Varint, sorted_ids_reject_bad_lists) {
    const std::uint64_t max = 1000;
    EXPECT_FALSE(decode_sorted_ids(Bytes{5, 0}, 2, max));           // repeated id
    EXPECT_FALSE(decode_sorted_ids(Bytes{5, 1}, 3, max));           // count too big for the bytes
    EXPECT_FALSE(decode_sorted_ids(Bytes{5, 1, 1}, 2, max));        // bytes left over
    EXPECT_FALSE(decode_sorted_ids(Bytes{0xe9, 0x07}, 1, max));     // 1001 > max
    EXPECT_FALSE(decode_sorted_ids(Bytes{0xe8, 0x07, 1}, 2, max));  // 1000 then 1001
    auto ok = decode_sorted_ids(Bytes{0xe8, 0x07}, 1, max);
    ASSERT_TRUE(ok);
    EXPECT_EQ(ok.value()[0], 1000u);
    EXPECT_TRUE(decode_sorted_ids(Bytes{}, 0, max));
}

TEST(Varint, sorted_ids_overflow_is_rejected) {
    Bytes bytes;
    append_varint(bytes, std::numeric_limits<std::uint64_t>::max());
    append_varint(bytes, 2);
    EXPECT_FALSE(decode_sorted_ids(bytes, 2, std::numeric_limits<std::uint64_t>::max()));
}

TEST(Varint, id_sequence_round_trips_any_order) {
    const std::vector<std::uint64_t> ids = {500, 498, 1000, 0, 7, (std::uint64_t{1} << 53) - 1, 3};
    const Bytes bytes = encode_id_sequence(ids, 490);
    auto decoded = decode_id_sequence(bytes, ids.size(), 490, (std::uint64_t{1} << 53) - 1);
    ASSERT_TRUE(decoded);
    EXPECT_EQ(decoded.value(), ids);
    // Small steps cost one byte: +10 -> zigzag 20, -2 -> zigzag 3.
    EXPECT_EQ(bytes[0], 20);
    EXPECT_EQ(bytes[1], 3);
}

TEST(Varint, id_sequence_rejects_out_of_range) {
    const Bytes bytes = encode_id_sequence(std::vector<std::uint64_t>{10, 2000}, 0);
    EXPECT_FALSE(decode_id_sequence(bytes, 2, 0, 1000));
    EXPECT_FALSE(decode_id_sequence(bytes, 1, 0, 5000));  // bytes left over
    const Bytes negative = encode_id_sequence(std::vector<std::uint64_t>{0}, 5);
    EXPECT_FALSE(decode_id_sequence(negative, 1, 4, 1000));  // 4 - 5 wraps past 2^64
}

}  // namespace
}  // namespace isomesh::protocol
