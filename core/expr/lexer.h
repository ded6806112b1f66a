// Lexer of the function language: UTF-8 text to tokens, one at a time, each with its 1-based line
// and column. Columns count code points, so `π` or `²` is one column, as the user sees it.
//
// Besides ASCII it reads the characters people paste from math text: `·` `⋅` `×` (times), `÷`,
// `−` (U+2212 minus), `π`, superscript exponents `x²` `x⁻¹` `x¹⁰`, `≤` `≥` `≠` (recognised only to
// be refused), the no-break space, and Greek letters in parameter names (`α`, `β`...).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace isomesh::expr {

enum class TokenKind {
    End,         // end of input
    Error,       // malformed input; Token::error says why
    Number,      // Token::number is its value (finite)
    Identifier,  // a name: variable, constant, function or parameter (`π` and `∞` stand alone)
    Plus,
    Minus,
    Star,
    Slash,
    Caret,
    Superscript,  // `²`, `⁻¹`...: Token::number is the whole exponent
    LeftParen,
    RightParen,
    Bar,  // `|`, opens or closes an absolute value
    Comma,
    Equals,
    Inequality,  // `<` `>` `<=` `>=` `!=` `≤` `≥` `≠`
};

struct Token {
    TokenKind kind = TokenKind::End;
    std::string_view text;  // the token's bytes in the source
    double number = 0.0;
    int line = 1;
    int column = 1;
    std::string error;  // for TokenKind::Error
};

class Lexer {
  public:
    explicit Lexer(std::string_view source);

    /// The next token, not consumed.
    const Token& peek() const { return current_; }
    /// Consumes and returns the next token. After End or Error, keeps returning it.
    Token take();
    /// True when the source spans several lines (messages then name the line).
    bool multiline() const { return multiline_; }

  private:
    Token scan();
    void skip_whitespace();
    void advance(std::size_t bytes);
    Token start_token(TokenKind kind) const;
    Token finish(Token token, std::size_t start) const;
    Token error(Token token, std::string message) const;
    Token scan_number(Token token);
    Token scan_identifier(Token token, char32_t first, std::size_t first_length);
    Token scan_superscript(Token token);
    Token scan_symbol(Token token, char32_t c, std::size_t length);

    std::string_view source_;
    std::size_t pos_ = 0;
    int line_ = 1;
    int column_ = 1;
    std::size_t split_until_ = 0;  // end of the x/y/z-only name being read letter by letter
    bool multiline_ = false;
    Token current_;
};

}  // namespace isomesh::expr
