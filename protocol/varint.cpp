// LEB128 varints and the two id-list codings of binary frames (see varint.h).
#include "protocol/varint.h"

#include <cassert>
#include <string>

namespace isomesh::protocol {
namespace {

Error frame_error(std::string message) {
    return Error{ErrorCode::bad_frame, std::move(message)};
}

std::uint64_t zigzag(std::uint64_t difference) {
    const auto signed_difference = static_cast<std::int64_t>(difference);
    return (difference << 1) ^ static_cast<std::uint64_t>(signed_difference >> 63);
}

std::uint64_t unzigzag(std::uint64_t value) {
    return (value >> 1) ^ (~(value & 1) + 1);
}

/// Checks that `count` values can fit in `bytes` at all (each takes at least one byte), before
/// anything is allocated for them.
std::optional<Error> check_count(std::span<const std::uint8_t> bytes, std::size_t count) {
    if (count > bytes.size()) {
        return frame_error(std::to_string(count) + " ids cannot fit in " +
                           std::to_string(bytes.size()) + " bytes");
    }
    return std::nullopt;
}

std::optional<Error> check_consumed(std::span<const std::uint8_t> bytes, std::size_t offset) {
    if (offset != bytes.size()) {
        return frame_error(std::to_string(bytes.size() - offset) + " bytes left after the ids");
    }
    return std::nullopt;
}

}  // namespace

void append_varint(std::vector<std::uint8_t>& out, std::uint64_t value) {
    while (value >= 0x80) {
        out.push_back(static_cast<std::uint8_t>(value | 0x80));
        value >>= 7;
    }
    out.push_back(static_cast<std::uint8_t>(value));
}

Result<std::uint64_t> read_varint(std::span<const std::uint8_t> bytes, std::size_t& offset) {
    std::uint64_t value = 0;
    for (std::size_t i = 0; i < kMaxVarintBytes; ++i) {
        if (offset + i >= bytes.size()) return frame_error("truncated varint");
        const std::uint8_t byte = bytes[offset + i];
        const std::uint64_t group = byte & 0x7f;
        if (i == kMaxVarintBytes - 1 && group > 1) return frame_error("varint exceeds 64 bits");
        value |= group << (7 * i);
        if ((byte & 0x80) == 0) {
            if (i > 0 && byte == 0) return frame_error("varint not in shortest form");
            offset += i + 1;
            return value;
        }
    }
    return frame_error("varint longer than 10 bytes");
}

std::vector<std::uint8_t> encode_sorted_ids(std::span<const std::uint64_t> ids) {
    std::vector<std::uint8_t> out;
    out.reserve(ids.size() * 2);
    std::uint64_t previous = 0;
    for (std::size_t i = 0; i < ids.size(); ++i) {
        assert(i == 0 || ids[i] > previous);
        append_varint(out, ids[i] - previous);
        previous = ids[i];
    }
    return out;
}

Result<std::vector<std::uint64_t>> decode_sorted_ids(std::span<const std::uint8_t> bytes,
                                                     std::size_t count, std::uint64_t max_id) {
    if (auto error = check_count(bytes, count)) return *error;
    std::vector<std::uint64_t> ids;
    ids.reserve(count);
    std::size_t offset = 0;
    std::uint64_t previous = 0;
    for (std::size_t i = 0; i < count; ++i) {
        auto step = read_varint(bytes, offset);
        if (!step) return step.error();
        if (i > 0 && step.value() == 0) return frame_error("removed ids not strictly ascending");
        if (step.value() > max_id - previous) return frame_error("removed id out of range");
        previous += step.value();
        ids.push_back(previous);
    }
    if (auto error = check_consumed(bytes, offset)) return *error;
    return ids;
}

std::vector<std::uint8_t> encode_id_sequence(std::span<const std::uint64_t> ids,
                                             std::uint64_t base) {
    std::vector<std::uint8_t> out;
    out.reserve(ids.size() * 2);
    std::uint64_t previous = base;
    for (std::uint64_t id : ids) {
        append_varint(out, zigzag(id - previous));
        previous = id;
    }
    return out;
}

Result<std::vector<std::uint64_t>> decode_id_sequence(std::span<const std::uint8_t> bytes,
                                                      std::size_t count, std::uint64_t base,
                                                      std::uint64_t max_id) {
    if (auto error = check_count(bytes, count)) return *error;
    std::vector<std::uint64_t> ids;
    ids.reserve(count);
    std::size_t offset = 0;
    std::uint64_t previous = base;
    for (std::size_t i = 0; i < count; ++i) {
        auto step = read_varint(bytes, offset);
        if (!step) return step.error();
        previous += unzigzag(step.value());  // modulo 2^64, as the encoder's subtraction
        if (previous > max_id) return frame_error("triangle id out of range");
        ids.push_back(previous);
    }
    if (auto error = check_consumed(bytes, offset)) return *error;
    return ids;
}

}  // namespace isomesh::protocol
