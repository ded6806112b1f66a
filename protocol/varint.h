// Variable-length integers for the id lists of binary frames (PROTOCOL.md, "Id lists").
//
// Unsigned LEB128: 7 bits per byte, least significant group first, high bit set on every byte but
// the last; at most 10 bytes for 64 bits, and only the shortest form is valid. Two list codings:
// - sorted lists (removed triangle ids): the first id, then each difference to the previous one,
//   which is >= 1 because the ids strictly ascend;
// - sequences in any order (explicit triangle ids): each id minus the previous one (the first
//   minus a base), zigzag-mapped to unsigned (0, -1, 1, -2, ... -> 0, 1, 2, 3, ...).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "protocol/errors.h"

namespace isomesh::protocol {

inline constexpr std::size_t kMaxVarintBytes = 10;

void append_varint(std::vector<std::uint8_t>& out, std::uint64_t value);

/// Reads one varint at `offset` and advances it. Fails (bad_frame) on truncation, on more than 64
/// bits and on a non-shortest form.
Result<std::uint64_t> read_varint(std::span<const std::uint8_t> bytes, std::size_t& offset);

/// Precondition: `ids` strictly ascending.
std::vector<std::uint8_t> encode_sorted_ids(std::span<const std::uint64_t> ids);

/// Decodes exactly `count` strictly ascending ids, each <= max_id, using all of `bytes`.
Result<std::vector<std::uint64_t>> decode_sorted_ids(std::span<const std::uint8_t> bytes,
                                                     std::size_t count, std::uint64_t max_id);

/// Any order; the first difference is taken from `base`.
std::vector<std::uint8_t> encode_id_sequence(std::span<const std::uint64_t> ids,
                                             std::uint64_t base);

/// Decodes exactly `count` ids, each <= max_id, using all of `bytes`. Does not check distinctness.
Result<std::vector<std::uint64_t>> decode_id_sequence(std::span<const std::uint8_t> bytes,
                                                      std::size_t count, std::uint64_t base,
                                                      std::uint64_t max_id);

}  // namespace isomesh::protocol
