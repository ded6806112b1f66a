// The request id of a message that cannot be parsed (malformed, nested too deeply, over the size
// limit of PROTOCOL.md section 8), found by a tolerant scan in constant memory for its error reply.
#include "protocol/request_id_scanner.h"

namespace isomesh::protocol {

namespace {
// A request id's value is at most 64 characters: 64 escapes of 12 bytes (\uXXXX\uXXXX) at most.
constexpr std::size_t kMaxIdValueBytes = 2 + 12 * kMaxRequestIdCharacters;
bool json_space(char c) {
    return c == ' ' || c == '\t' || c == '\n' || c == '\r';
}
}  // namespace

void RequestIdScanner::feed(std::string_view text) {
    for (char c : text) {
        if (done_) return;
        if (in_string_) {
            if (depth_ == 1) capture(c);
            if (escaped_) {
                escaped_ = false;
            } else if (c == '\\') {
                escaped_ = true;
            } else if (c == '"') {
                in_string_ = false;
                if (depth_ == 1) top_level(c);
            }
        } else if (c == '"') {
            in_string_ = true;
            if (depth_ == 1) top_level(c);
        } else if (c == '{' || c == '[') {
            if (depth_ == 1 && phase_ == Phase::before_value && key_is_id_) done_ = true;
            if (depth_ == 1 && phase_ == Phase::before_value) phase_ = Phase::after_value;
            ++depth_;
        } else if (c == '}' || c == ']') {
            if (depth_ == 1) top_level(c);
            --depth_;
        } else if (depth_ == 1) {
            top_level(c);
        }
    }
}

/// A character outside strings at depth 1, or a quote opening or closing a string there.
void RequestIdScanner::top_level(char c) {
    switch (phase_) {
        case Phase::before_key:
            if (c == '"') phase_ = Phase::in_key, key_.clear();
            break;
        case Phase::in_key:  // the closing quote (the key's characters went to capture)
            key_is_id_ = key_ == "id";
            phase_ = Phase::after_key;
            break;
        case Phase::after_key:
            if (c == ':') phase_ = Phase::before_value;
            break;
        case Phase::before_value:
            if (json_space(c)) break;
            phase_ = Phase::in_value;
            value_is_string_ = c == '"';
            value_.clear();
            if (!value_is_string_) capture(c);
            break;
        case Phase::in_value:
            if (value_is_string_ || c == ',' || c == '}' || json_space(c)) {
                if (key_is_id_) done_ = true;
                phase_ = c == ',' ? Phase::before_key : Phase::after_value;
            } else {
                capture(c);
            }
            break;
        case Phase::after_value:
            if (c == ',') phase_ = Phase::before_key;
            break;
    }
}

void RequestIdScanner::capture(char c) {
    if (phase_ == Phase::in_key) {
        if (c != '"' && key_.size() < 3)
            key_ += c;
        else if (c != '"')
            key_ = "???";  // longer than "id"
    } else if (phase_ == Phase::in_value && key_is_id_) {
        if (value_.size() >= kMaxIdValueBytes) {
            done_ = true;
            value_.clear();
            return;
        }
        value_ += c;
    }
}

std::optional<RequestId> RequestIdScanner::id() const {
    if (!done_ || !key_is_id_ || value_.empty()) return std::nullopt;
    return parse_request_id(value_is_string_ ? "\"" + value_ : value_);
}

std::optional<RequestId> scan_request_id(std::string_view text) {
    RequestIdScanner scanner;
    scanner.feed(text);
    return scanner.id();
}

}  // namespace isomesh::protocol
