// The adaptive binary range coder of version-2 delta frames (see range_coder.h).
#include "protocol/range_coder.h"

#include <array>
#include <bit>
#include <cassert>
#include <cmath>

namespace isomesh::protocol {
namespace {

constexpr int kProbabilityBits = 11;
constexpr std::uint32_t kOne = 1u << kProbabilityBits;
constexpr int kAdaptShift = 5;
constexpr std::uint32_t kTop = 1u << 24;
constexpr int kMaxLength = 62;

void adapt(BitModel& model, bool bit) {
    if (bit) {
        model.p = static_cast<std::uint16_t>(model.p - (model.p >> kAdaptShift));
    } else {
        model.p = static_cast<std::uint16_t>(model.p + ((kOne - model.p) >> kAdaptShift));
    }
}

/// The information content of a bit coded with probability p / 2^11, in bits: -log2(p / 2^11),
/// tabulated (statistics charge every bit; log2 was a tenth of a delta's encoding time).
double information_bits(std::uint32_t p) {
    static const std::array<double, kOne + 1> table = [] {
        std::array<double, kOne + 1> t{};
        for (std::uint32_t i = 1; i <= kOne; ++i) t[i] = -std::log2(i / double(kOne));
        return t;
    }();
    return table[p];
}

std::uint64_t zigzag(std::int64_t value) {
    return (static_cast<std::uint64_t>(value) << 1) ^ static_cast<std::uint64_t>(value >> 63);
}

std::int64_t unzigzag(std::uint64_t value) {
    return static_cast<std::int64_t>(value >> 1) ^ -static_cast<std::int64_t>(value & 1);
}

}  // namespace

// ---- encoder ----------------------------------------------------------------------------------

void RangeEncoder::shift_low() {
    if (static_cast<std::uint32_t>(low_) < 0xFF000000u || (low_ >> 32) != 0) {
        const auto carry = static_cast<std::uint8_t>(low_ >> 32);
        std::uint8_t byte = cache_;
        do {
            out_.push_back(static_cast<std::uint8_t>(byte + carry));
            byte = 0xFF;
        } while (--cache_size_ != 0);
        cache_ = static_cast<std::uint8_t>(low_ >> 24);
    }
    ++cache_size_;
    low_ = (low_ & 0x00FFFFFFu) << 8;
}

void RangeEncoder::normalize() {
    while (range_ < kTop) {
        range_ <<= 8;
        shift_low();
    }
}

void RangeEncoder::bit(BitModel& model, bool bit) {
    const std::uint32_t bound = (range_ >> kProbabilityBits) * model.p;
    if (sink_) *sink_ += information_bits(bit ? kOne - model.p : model.p);
    if (bit) {
        low_ += bound;
        range_ -= bound;
    } else {
        range_ = bound;
    }
    adapt(model, bit);
    normalize();
}

void RangeEncoder::direct(std::uint32_t value, int count) {
    assert(count >= 0 && count <= 32);
    if (sink_) *sink_ += count;
    for (int i = count - 1; i >= 0; --i) {
        range_ >>= 1;
        if ((value >> i) & 1) low_ += range_;
        normalize();
    }
}

void RangeEncoder::uint(IntModel& model, std::uint64_t value) {
    assert(value < (std::uint64_t{1} << kMaxLength));
    const std::uint64_t v = value + 1;
    const int length = std::bit_width(v) - 1;  // v in [2^length, 2^(length + 1))
    for (int i = 0; i < length; ++i) bit(model.length[std::min<int>(i, 23)], true);
    bit(model.length[std::min(length, 23)], false);
    if (length == 0) return;
    bit(model.high[length], (v >> (length - 1)) & 1);
    for (int i = length - 2; i >= 0; i -= 32) {
        const int count = std::min(i + 1, 32);
        direct(static_cast<std::uint32_t>(v >> (i + 1 - count)) &
                   (count == 32 ? 0xFFFFFFFFu : (1u << count) - 1),
               count);
    }
}

void RangeEncoder::sint(IntModel& model, std::int64_t value) {
    uint(model, zigzag(value));
}

std::vector<std::uint8_t> RangeEncoder::finish() {
    for (int i = 0; i < 5; ++i) shift_low();
    return std::move(out_);
}

// ---- decoder ----------------------------------------------------------------------------------

RangeDecoder::RangeDecoder(std::span<const std::uint8_t> bytes) : bytes_(bytes) {
    if (bytes.size() < 5 || bytes[0] != 0) ok_ = false;
    for (int i = 0; i < 5; ++i) code_ = (code_ << 8) | next();
}

std::uint8_t RangeDecoder::next() {
    if (offset_ < bytes_.size()) return bytes_[offset_++];
    ++overrun_;
    return 0;
}

void RangeDecoder::normalize() {
    if (range_ < kTop) {
        range_ <<= 8;
        code_ = (code_ << 8) | next();
    }
}

bool RangeDecoder::bit(BitModel& model) {
    const std::uint32_t bound = (range_ >> kProbabilityBits) * model.p;
    bool bit;
    if (code_ < bound) {
        range_ = bound;
        bit = false;
    } else {
        code_ -= bound;
        range_ -= bound;
        bit = true;
    }
    adapt(model, bit);
    normalize();
    return bit;
}

std::uint32_t RangeDecoder::direct(int count) {
    std::uint32_t value = 0;
    for (int i = 0; i < count; ++i) {
        range_ >>= 1;
        const bool bit = code_ >= range_;
        if (bit) code_ -= range_;
        value = (value << 1) | (bit ? 1u : 0u);
        normalize();
    }
    return value;
}

std::uint64_t RangeDecoder::uint(IntModel& model) {
    int length = 0;
    while (bit(model.length[std::min(length, 23)])) {
        if (++length > kMaxLength) {
            ok_ = false;
            return 0;
        }
    }
    if (length == 0) return 0;
    std::uint64_t v = 2 | (bit(model.high[length]) ? 1 : 0);
    for (int i = length - 2; i >= 0; i -= 32) {
        const int count = std::min(i + 1, 32);
        v = (v << count) | direct(count);
    }
    return v - 1;
}

std::int64_t RangeDecoder::sint(IntModel& model) {
    return unzigzag(uint(model));
}

}  // namespace isomesh::protocol
