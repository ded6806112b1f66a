#include "server/close_code_filter.h"

#include <algorithm>

namespace isomesh::server {
namespace {

constexpr std::uint8_t kCloseOpcode = 0x8;
constexpr std::uint16_t kReplacement = 1005;  // reserved: never valid on the wire

}  // namespace

bool valid_close_code(std::uint16_t code) {
    return (code >= 1000 && code <= 1003) || (code >= 1007 && code <= 1014) ||
           (code >= 3000 && code <= 4999);
}

std::size_t CloseCodeFilter::filter(std::span<std::uint8_t> bytes) {
    std::size_t i = 0;
    while (i < bytes.size()) {
        if (state_ != State::payload) {
            header_byte(bytes[i++]);
            continue;
        }
        if (close_ && offset_ == 0 && length_ >= 2) {
            if (i + 1 == bytes.size()) return i;  // the code's second byte is still to come
            code(bytes[i], bytes[i + 1]);
        }
        // The rest of the payload passes unread.
        const std::uint64_t skip = std::min<std::uint64_t>(length_ - offset_, bytes.size() - i);
        i += static_cast<std::size_t>(skip);
        offset_ += skip;
        if (offset_ == length_) state_ = State::opcode;
    }
    return i;
}

void CloseCodeFilter::header_byte(std::uint8_t byte) {
    switch (state_) {
        case State::opcode:
            close_ = (byte & 0x0F) == kCloseOpcode;
            state_ = State::length;
            break;
        case State::length:
            masked_ = (byte & 0x80) != 0;
            length_ = byte & 0x7F;
            length_bytes_ = length_ == 126 ? 2 : length_ == 127 ? 8 : 0;
            if (length_bytes_ > 0) {
                length_ = 0;
                state_ = State::extended_length;
            } else {
                start_payload();
            }
            break;
        case State::extended_length:
            length_ = (length_ << 8) | byte;
            if (--length_bytes_ == 0) start_payload();
            break;
        case State::mask:
            key_[mask_bytes_++] = byte;
            if (mask_bytes_ == 4) {
                state_ = State::payload;
                if (length_ == 0) state_ = State::opcode;
            }
            break;
        case State::payload:
            break;
    }
}

void CloseCodeFilter::start_payload() {
    offset_ = 0;
    mask_bytes_ = 0;
    key_ = {};
    if (masked_) {
        state_ = State::mask;
    } else {
        state_ = length_ == 0 ? State::opcode : State::payload;
    }
}

void CloseCodeFilter::code(std::uint8_t& high, std::uint8_t& low) {
    const auto byte = [&](std::uint8_t masked, int i) {
        return static_cast<std::uint16_t>(masked_ ? masked ^ key_[i] : masked);
    };
    const std::uint16_t code = static_cast<std::uint16_t>(byte(high, 0) << 8 | byte(low, 1));
    if (valid_close_code(code)) return;
    high = static_cast<std::uint8_t>(byte(kReplacement >> 8, 0));
    low = static_cast<std::uint8_t>(byte(kReplacement & 0xFF, 1));
}

}  // namespace isomesh::server
