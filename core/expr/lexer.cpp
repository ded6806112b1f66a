#include "expr/lexer.h"

#include <charconv>
#include <cstdio>

#include "expr/utf8.h"

namespace isomesh::expr {

namespace {

constexpr char32_t kPi = U'\u03C0';
constexpr char32_t kInfinity = U'\u221E';
constexpr char32_t kSuperscriptMinus = U'\u207B';

bool is_ascii_letter(char32_t c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z');
}
bool is_digit(char32_t c) {
    return c >= '0' && c <= '9';
}

bool is_greek_letter(char32_t c) {
    bool upper = c >= U'\u0391' && c <= U'\u03A9' && c != U'\u03A2';
    bool lower = c >= U'\u03B1' && c <= U'\u03C9';
    return (upper || lower) && c != kPi;
}

bool is_identifier_start(char32_t c) {
    return is_ascii_letter(c) || is_greek_letter(c);
}
bool is_identifier_part(char32_t c) {
    return is_identifier_start(c) || is_digit(c) || c == '_';
}

bool is_whitespace(char32_t c) {
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v' ||
           c == U'\u00A0' || c == U'\u2009' || c == U'\u202F';
}

/// The digit a superscript character stands for, or -1.
int superscript_digit(char32_t c) {
    switch (c) {
        case U'\u2070':
            return 0;
        case U'\u00B9':
            return 1;
        case U'\u00B2':
            return 2;
        case U'\u00B3':
            return 3;
        default:
            return (c >= U'\u2074' && c <= U'\u2079') ? static_cast<int>(c - U'\u2070') : -1;
    }
}

TokenKind symbol_kind(char32_t c) {
    switch (c) {
        case '+':
            return TokenKind::Plus;
        case '-':
        case U'\u2212':
            return TokenKind::Minus;
        case '*':
        case U'\u00B7':
        case U'\u22C5':
        case U'\u00D7':
            return TokenKind::Star;
        case '/':
        case U'\u00F7':
            return TokenKind::Slash;
        case '^':
            return TokenKind::Caret;
        case '(':
            return TokenKind::LeftParen;
        case ')':
            return TokenKind::RightParen;
        case '|':
            return TokenKind::Bar;
        case ',':
            return TokenKind::Comma;
        case '=':
            return TokenKind::Equals;
        case '<':
        case '>':
        case U'\u2264':
        case U'\u2265':
        case U'\u2260':
            return TokenKind::Inequality;
        default:
            return TokenKind::Error;
    }
}

std::string describe_character(std::string_view bytes, char32_t c) {
    if (c >= 0x20 && c != 0x7F && !(c >= 0x80 && c < 0xA0)) return quote(bytes);
    char buffer[16];
    std::snprintf(buffer, sizeof buffer, "U+%04X", static_cast<unsigned>(c));
    return buffer;
}

}  // namespace

Lexer::Lexer(std::string_view source) : source_(source) {
    multiline_ = source.find('\n') != std::string_view::npos;
    current_ = scan();
}

Token Lexer::take() {
    Token token = current_;
    if (token.kind != TokenKind::End && token.kind != TokenKind::Error) current_ = scan();
    return token;
}

void Lexer::advance(std::size_t bytes) {
    if (source_[pos_] == '\n') {
        ++line_;
        column_ = 1;
    } else {
        ++column_;
    }
    pos_ += bytes;
}

void Lexer::skip_whitespace() {
    while (pos_ < source_.size()) {
        CodePoint c = decode_utf8(source_, pos_);
        if (c.length == 0 || !is_whitespace(c.value)) return;
        advance(c.length);
    }
}

Token Lexer::start_token(TokenKind kind) const {
    Token token;
    token.kind = kind;
    token.line = line_;
    token.column = column_;
    token.text = source_.substr(pos_, 0);
    return token;
}

Token Lexer::finish(Token token, std::size_t start) const {
    token.text = source_.substr(start, pos_ - start);
    return token;
}

Token Lexer::error(Token token, std::string message) const {
    token.kind = TokenKind::Error;
    token.error = std::move(message);
    return token;
}

Token Lexer::scan() {
    skip_whitespace();
    Token token = start_token(TokenKind::End);
    if (pos_ >= source_.size()) return token;
    CodePoint c = decode_utf8(source_, pos_);
    if (c.length == 0) return error(token, "invalid UTF-8");
    if (is_digit(c.value) || c.value == '.') return scan_number(token);
    if (is_identifier_start(c.value) || c.value == kPi || c.value == kInfinity)
        return scan_identifier(token, c.value, c.length);
    if (superscript_digit(c.value) >= 0 || c.value == kSuperscriptMinus)
        return scan_superscript(token);
    return scan_symbol(token, c.value, c.length);
}

Token Lexer::scan_number(Token token) {
    std::size_t start = pos_;
    auto at = [&](std::size_t p) { return p < source_.size() ? source_[p] : '\0'; };
    int points = 0;
    while (is_digit(static_cast<unsigned char>(at(pos_))) || at(pos_) == '.') {
        points += at(pos_) == '.';
        advance(1);
    }
    // An exponent only when digits follow: `2e` is 2 times e and `2e-x` is 2e - x.
    std::size_t digits = pos_ + 1 + ((at(pos_ + 1) == '+' || at(pos_ + 1) == '-') ? 1 : 0);
    if ((at(pos_) == 'e' || at(pos_) == 'E') && is_digit(static_cast<unsigned char>(at(digits)))) {
        while (pos_ < digits) advance(1);
        while (is_digit(static_cast<unsigned char>(at(pos_)))) advance(1);
    }
    token = finish(token, start);
    token.kind = TokenKind::Number;
    if (points > 1 || token.text == ".")
        return error(token, "malformed number " + quote(token.text));
    auto [end, status] =
        std::from_chars(token.text.data(), token.text.data() + token.text.size(), token.number);
    if (status != std::errc{} || end != token.text.data() + token.text.size())
        return error(token, "number out of range " + quote(token.text));
    return token;
}

Token Lexer::scan_identifier(Token token, char32_t first, std::size_t first_length) {
    std::size_t start = pos_;
    token.kind = TokenKind::Identifier;
    std::size_t end = pos_ + first_length;
    bool alone = first == kPi || first == kInfinity || pos_ < split_until_;
    while (!alone && end < source_.size()) {
        CodePoint c = decode_utf8(source_, end);
        if (c.length == 0 || !is_identifier_part(c.value)) break;
        end += c.length;
    }
    // A name made only of x, y and z is their product: each letter is a token of its own, so
    // `xy^2` reads as `x y^2`, as GeoGebra reads it.
    std::string_view name = source_.substr(start, end - start);
    if (!alone && name.find_first_not_of("xyz") == std::string_view::npos) {
        split_until_ = end;
        end = start + 1;
    }
    while (pos_ < end) advance(decode_utf8(source_, pos_).length);
    return finish(token, start);
}

Token Lexer::scan_superscript(Token token) {
    std::size_t start = pos_;
    token.kind = TokenKind::Superscript;
    bool negative = decode_utf8(source_, pos_).value == kSuperscriptMinus;
    if (negative) advance(decode_utf8(source_, pos_).length);
    int digits = 0;
    double exponent = 0.0;
    while (pos_ < source_.size()) {
        CodePoint c = decode_utf8(source_, pos_);
        int digit = c.length == 0 ? -1 : superscript_digit(c.value);
        if (digit < 0) break;
        exponent = exponent * 10.0 + digit;
        ++digits;
        advance(c.length);
    }
    token = finish(token, start);
    if (digits == 0) return error(token, "superscript minus without digits");
    if (digits > 4) return error(token, "superscript exponent too large " + quote(token.text));
    token.number = negative ? -exponent : exponent;
    return token;
}

Token Lexer::scan_symbol(Token token, char32_t c, std::size_t length) {
    std::size_t start = pos_;
    advance(length);
    token.kind = symbol_kind(c);
    bool two_char =
        (c == '<' || c == '>' || c == '!') && pos_ < source_.size() && source_[pos_] == '=';
    if (two_char) {
        advance(1);
        token.kind = TokenKind::Inequality;
    }
    token = finish(token, start);
    if (token.kind == TokenKind::Error)
        return error(token, "unexpected character " + describe_character(token.text, c));
    return token;
}

}  // namespace isomesh::expr
