// UTF-8 decoding (RFC 3629) for the expression lexer, and quoting of source text in messages.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace isomesh::expr {

/// One decoded code point; `length` is 0 when the bytes at the position are not valid UTF-8
/// (bad lead byte, truncated sequence, overlong form, surrogate, or beyond U+10FFFF).
struct CodePoint {
    char32_t value = 0;
    std::size_t length = 0;
};

/// Decodes the code point starting at text[pos]. Precondition: pos < text.size().
CodePoint decode_utf8(std::string_view text, std::size_t pos);

/// `text` in single quotes for an error message: at most `max_chars` code points (then "..."),
/// control characters and bytes that are not valid UTF-8 written as \xNN, so a message is always
/// short, printable, valid UTF-8.
std::string quote(std::string_view text, std::size_t max_chars = 32);

}  // namespace isomesh::expr
