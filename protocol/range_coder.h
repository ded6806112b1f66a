// The entropy coder of version-2 delta frames (PROTOCOL.md, "Delta frames, version 2"): an
// adaptive binary range coder, the one of LZMA (Pavlov; the "rc" of the 7-Zip SDK), with 11-bit
// probabilities adapted by 1/32 of the error after every bit, and integers written as adaptive
// Exp-Golomb codes on top of it.
//
// Why our own coder rather than Draco's: a delta names vertices and triangles the client already
// holds, which a Draco bitstream cannot reference (it encodes a self-contained mesh), and the
// values it carries are residuals of predictions made from that held mesh. Only integer arithmetic
// is involved, so any language decodes it bit-exactly (clients/js/src/range_decoder.js).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace isomesh::protocol {

/// A probability that the next bit is 0, in units of 2^-11.
struct BitModel {
    std::uint16_t p = 1024;
};

/// The contexts of one kind of integer: the unary prefix (the value's bit length) and the first
/// bit below the leading one, by length. Lengths beyond 63 are invalid.
struct IntModel {
    std::array<BitModel, 24> length;
    std::array<BitModel, 64> high;
};

class RangeEncoder {
  public:
    void bit(BitModel& model, bool bit);
    /// `count` (<= 32) bits of `value`, most significant first, each with probability 1/2.
    void direct(std::uint32_t value, int count);
    /// An unsigned integer < 2^63 (adaptive Exp-Golomb: bit length in unary, the bit after the
    /// leading one adaptive, the rest direct).
    void uint(IntModel& model, std::uint64_t value);
    /// A signed integer, zigzag-mapped (0, -1, 1, -2, ... -> 0, 1, 2, 3, ...).
    void sint(IntModel& model, std::int64_t value);
    /// Flushes the coder and returns its bytes.
    std::vector<std::uint8_t> finish();
    /// From now on, adds the information content of every coded bit (in bits) to `*sink` (for
    /// statistics of where the bytes go; nullptr stops).
    void charge_to(double* sink) { sink_ = sink; }

  private:
    void shift_low();
    void normalize();

    std::uint64_t low_ = 0;
    std::uint32_t range_ = 0xFFFFFFFFu;
    std::uint8_t cache_ = 0;
    std::uint64_t cache_size_ = 1;
    std::vector<std::uint8_t> out_;
    double* sink_ = nullptr;
};

class RangeDecoder {
  public:
    /// Reads the first 5 bytes; ok() is false when there are fewer or the first is not 0.
    explicit RangeDecoder(std::span<const std::uint8_t> bytes);
    bool bit(BitModel& model);
    std::uint32_t direct(int count);
    /// An unsigned integer; sets ok() false on a bit length over 62.
    std::uint64_t uint(IntModel& model);
    std::int64_t sint(IntModel& model);
    /// False once the stream was malformed or read more than 4 bytes past its end (a valid stream
    /// never needs more than the encoder's 5 flush bytes, which it carries).
    bool ok() const { return ok_ && overrun_ <= 4; }

  private:
    std::uint8_t next();
    void normalize();

    std::span<const std::uint8_t> bytes_;
    std::size_t offset_ = 0;
    std::size_t overrun_ = 0;
    std::uint32_t range_ = 0xFFFFFFFFu;
    std::uint32_t code_ = 0;
    bool ok_ = true;
};

}  // namespace isomesh::protocol
