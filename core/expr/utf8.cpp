#include "expr/utf8.h"

#include <cstdio>

namespace isomesh::expr {

namespace {

/// Number of continuation bytes and the smallest value allowed (to reject overlong forms) for a
/// lead byte; continuation_count < 0 for a byte that cannot start a sequence.
struct LeadByte {
    int continuation_count;
    char32_t minimum;
    char32_t initial_bits;
};

LeadByte classify_lead(unsigned char byte) {
    if (byte < 0x80) return {0, 0, byte};
    if ((byte & 0xE0) == 0xC0) return {1, 0x80, byte & 0x1Fu};
    if ((byte & 0xF0) == 0xE0) return {2, 0x800, byte & 0x0Fu};
    if ((byte & 0xF8) == 0xF0) return {3, 0x10000, byte & 0x07u};
    return {-1, 0, 0};
}

bool is_control(char32_t c) {
    return c < 0x20 || c == 0x7F || (c >= 0x80 && c < 0xA0);
}

void append_escaped_byte(std::string& out, unsigned char byte) {
    char buffer[8];
    std::snprintf(buffer, sizeof buffer, "\\x%02X", byte);
    out += buffer;
}

}  // namespace

CodePoint decode_utf8(std::string_view text, std::size_t pos) {
    LeadByte lead = classify_lead(static_cast<unsigned char>(text[pos]));
    if (lead.continuation_count < 0) return {};
    if (text.size() - pos <= static_cast<std::size_t>(lead.continuation_count)) return {};
    char32_t value = lead.initial_bits;
    for (int k = 1; k <= lead.continuation_count; ++k) {
        auto byte = static_cast<unsigned char>(text[pos + static_cast<std::size_t>(k)]);
        if ((byte & 0xC0) != 0x80) return {};
        value = (value << 6) | (byte & 0x3Fu);
    }
    bool surrogate = value >= 0xD800 && value <= 0xDFFF;
    if (value < lead.minimum || surrogate || value > 0x10FFFF) return {};
    return {value, static_cast<std::size_t>(lead.continuation_count) + 1};
}

std::string quote(std::string_view text, std::size_t max_chars) {
    std::string out = "'";
    std::size_t pos = 0;
    for (std::size_t chars = 0; pos < text.size() && chars < max_chars; ++chars) {
        CodePoint c = decode_utf8(text, pos);
        if (c.length == 0 || is_control(c.value)) {
            std::size_t bytes = c.length == 0 ? 1 : c.length;
            for (std::size_t k = 0; k < bytes; ++k)
                append_escaped_byte(out, static_cast<unsigned char>(text[pos + k]));
            pos += bytes;
            continue;
        }
        out.append(text.substr(pos, c.length));
        pos += c.length;
    }
    if (pos < text.size()) out += "...";
    return out + "'";
}

}  // namespace isomesh::expr
