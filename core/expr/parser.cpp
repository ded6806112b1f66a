#include "expr/parser.h"

#include <unordered_set>
#include <vector>

#include "expr/lexer.h"
#include "expr/utf8.h"

namespace isomesh::expr {

namespace {

constexpr int kAdditive = 10;
constexpr int kMultiplicative = 20;
constexpr int kPrefix = 30;
constexpr int kPower = 40;

struct BinaryOperator {
    Op op;
    int power;
};

/// The written binary operators + - * / (not ^, which is right-associative, nor juxtaposition).
std::optional<BinaryOperator> explicit_operator(TokenKind kind) {
    switch (kind) {
        case TokenKind::Plus:
            return BinaryOperator{Op::Add, kAdditive};
        case TokenKind::Minus:
            return BinaryOperator{Op::Sub, kAdditive};
        case TokenKind::Star:
            return BinaryOperator{Op::Mul, kMultiplicative};
        case TokenKind::Slash:
            return BinaryOperator{Op::Div, kMultiplicative};
        default:
            return std::nullopt;
    }
}

/// Thrown at the first error and caught by parse_equation: the parser stops there.
struct ParseFailure {
    CompileError error;
};

/// The axis of a variable name (x = 0, y = 1, z = 2), or -1.
int variable_axis(std::string_view name) {
    if (name.size() != 1 || name[0] < 'x' || name[0] > 'z') return -1;
    return name[0] - 'x';
}

/// Letters in a name (code points other than digits and '_'): `foo(x)` with more than one letter
/// is an unknown function, `a(x)` or `a1(x)` a parameter times (x).
int letter_count(std::string_view name) {
    int letters = 0;
    for (char c : name) {
        auto byte = static_cast<unsigned char>(c);
        bool continuation = (byte & 0xC0) == 0x80;
        letters += !continuation && !(c >= '0' && c <= '9') && c != '_';
    }
    return letters;
}

std::string plural(std::size_t n, std::string_view word) {
    return std::to_string(n) + " " + std::string(word) + (n == 1 ? "" : "s");
}

std::string arity_message(const FunctionInfo& f, std::size_t got) {
    std::string takes;
    if (f.max_args < 0)
        takes = "at least " + plural(static_cast<std::size_t>(f.min_args), "argument");
    else if (f.min_args == f.max_args)
        takes = plural(static_cast<std::size_t>(f.min_args), "argument");
    else
        takes = std::to_string(f.min_args) + " or " +
                plural(static_cast<std::size_t>(f.max_args), "argument");
    return std::string(f.name) + " takes " + takes + ", got " + std::to_string(got);
}

class Parser {
  public:
    Parser(std::string_view source, const CompileLimits& limits, TapeBuilder& builder)
        : lexer_(source), limits_(limits), builder_(builder) {}

    Slot equation();

  private:
    /// Counts one level of nesting for as long as it lives.
    class Nesting {
      public:
        Nesting(Parser& parser, const Token& at);
        ~Nesting() { --parser_.depth_; }
        Nesting(const Nesting&) = delete;
        Nesting& operator=(const Nesting&) = delete;

      private:
        Parser& parser_;
    };

    Slot expression(int min_power);
    int infix_power(const Token& token) const;
    Slot infix(Slot left);
    Slot prefix();
    Slot signed_operand(const Token& sign);
    Slot group(const Token& open);
    Slot absolute_value(const Token& open);
    Slot name(const Token& token);
    Slot parameter(const Token& token);
    Slot call(const Token& token, const FunctionInfo& function);
    std::vector<Slot> arguments(const Token& open);
    void close(TokenKind kind, const Token& open);
    Slot checked(Slot slot);
    [[noreturn]] void fail(const Token& at, std::string message) const;
    [[noreturn]] void fail_unexpected(const Token& token) const;

    Lexer lexer_;
    const CompileLimits& limits_;
    TapeBuilder& builder_;
    int depth_ = 0;
    int open_bars_ = 0;  // bars opened at the current bracket level: a `|` after an operand closes
    bool seen_equals_ = false;
    std::unordered_set<std::string_view> parameters_;
};

Parser::Nesting::Nesting(Parser& parser, const Token& at) : parser_(parser) {
    if (++parser_.depth_ > parser_.limits_.max_depth)
        parser_.fail(
            at, "nesting deeper than " + std::to_string(parser_.limits_.max_depth) + " levels");
}

void Parser::fail(const Token& at, std::string message) const {
    throw ParseFailure{CompileError{std::move(message), at.line, at.column, lexer_.multiline()}};
}

void Parser::fail_unexpected(const Token& token) const {
    switch (token.kind) {
        case TokenKind::Error:
            fail(token, token.error);
        case TokenKind::End:
            fail(token, "unexpected end of input");
        case TokenKind::Equals:
            fail(token, seen_equals_ ? "more than one '='" : "unexpected '='");
        case TokenKind::Inequality:
            fail(token, "inequalities describe regions, not surfaces: use '=' instead of " +
                            quote(token.text));
        default:
            fail(token, "unexpected " + quote(token.text));
    }
}

Slot Parser::checked(Slot slot) {
    if (builder_.size() > limits_.max_instructions) {
        throw ParseFailure{CompileError{"the expression needs more than " +
                                            std::to_string(limits_.max_instructions) +
                                            " instructions",
                                        1, 0, false}};
    }
    return slot;
}

Slot Parser::equation() {
    if (lexer_.peek().kind == TokenKind::End)
        throw ParseFailure{CompileError{"empty input", 1, 0, false}};
    Slot lhs = expression(0);
    Token token = lexer_.take();
    if (token.kind == TokenKind::End) return lhs;
    if (token.kind != TokenKind::Equals) fail_unexpected(token);
    seen_equals_ = true;
    Slot rhs = expression(0);
    token = lexer_.take();
    if (token.kind != TokenKind::End) fail_unexpected(token);
    return checked(builder_.binary(Op::Sub, lhs, rhs));
}

Slot Parser::expression(int min_power) {
    Slot left = checked(prefix());
    while (infix_power(lexer_.peek()) > min_power) left = checked(infix(left));
    return left;
}

int Parser::infix_power(const Token& token) const {
    if (std::optional<BinaryOperator> binary = explicit_operator(token.kind)) return binary->power;
    switch (token.kind) {
        case TokenKind::Caret:
        case TokenKind::Superscript:
            return kPower;
        // Juxtaposition: an operand right after an operand multiplies it.
        case TokenKind::Number:
        case TokenKind::Identifier:
        case TokenKind::LeftParen:
            return kMultiplicative;
        case TokenKind::Bar:
            return open_bars_ > 0 ? 0 : kMultiplicative;
        default:
            return 0;
    }
}

Slot Parser::infix(Slot left) {
    const Token& next = lexer_.peek();
    if (std::optional<BinaryOperator> binary = explicit_operator(next.kind)) {
        lexer_.take();
        return builder_.binary(binary->op, left, expression(binary->power));
    }
    if (next.kind == TokenKind::Caret) {
        Token caret = lexer_.take();
        Nesting nesting(*this, caret);
        return emit_power(builder_, left, expression(kPower - 1));  // right-associative
    }
    if (next.kind == TokenKind::Superscript)
        return emit_power(builder_, left, builder_.constant(lexer_.take().number));
    return builder_.binary(Op::Mul, left, expression(kMultiplicative));  // juxtaposition
}

Slot Parser::prefix() {
    Token token = lexer_.take();
    switch (token.kind) {
        case TokenKind::Number:
            return builder_.constant(token.number);
        case TokenKind::Identifier:
            return name(token);
        case TokenKind::LeftParen:
            return group(token);
        case TokenKind::Bar:
            return absolute_value(token);
        case TokenKind::Minus:
        case TokenKind::Plus:
            return signed_operand(token);
        default:
            fail_unexpected(token);
    }
}

Slot Parser::signed_operand(const Token& sign) {
    Nesting nesting(*this, sign);
    Slot operand = expression(kPrefix);
    return sign.kind == TokenKind::Minus ? builder_.unary(Op::Neg, operand) : operand;
}

Slot Parser::group(const Token& open) {
    Nesting nesting(*this, open);
    int outer_bars = open_bars_;
    open_bars_ = 0;
    Slot inner = expression(0);
    close(TokenKind::RightParen, open);
    open_bars_ = outer_bars;
    return inner;
}

Slot Parser::absolute_value(const Token& open) {
    Nesting nesting(*this, open);
    ++open_bars_;
    Slot inner = expression(0);
    close(TokenKind::Bar, open);
    --open_bars_;
    return builder_.unary(Op::Abs, inner);
}

void Parser::close(TokenKind kind, const Token& open) {
    Token token = lexer_.take();
    if (token.kind == kind) return;
    if (token.kind == TokenKind::End) fail(open, "unclosed " + quote(open.text));
    fail_unexpected(token);
}

Slot Parser::name(const Token& token) {
    std::string_view text = token.text;
    if (is_non_finite_name(text)) fail(token, quote(text) + " is not a finite number");
    if (const FunctionInfo* function = find_function(text)) return call(token, *function);
    double value = 0.0;
    if (find_constant(text, value)) return builder_.constant(value);
    if (int axis = variable_axis(text); axis >= 0) return builder_.var(axis);
    if (lexer_.peek().kind == TokenKind::LeftParen && letter_count(text) > 1)
        fail(token, "unknown function " + quote(text));
    return parameter(token);
}

Slot Parser::parameter(const Token& token) {
    if (parameters_.insert(token.text).second && parameters_.size() > limits_.max_parameters)
        fail(token, "more than " + std::to_string(limits_.max_parameters) + " parameters");
    return builder_.param(token.text);
}

Slot Parser::call(const Token& token, const FunctionInfo& function) {
    // sin²(x) = sin(x)^2; sin⁻¹(x) is refused: it means asin(x) to some and 1/sin(x) to others.
    std::optional<Token> power;
    if (lexer_.peek().kind == TokenKind::Superscript) {
        power = lexer_.take();
        if (power->number < 0)
            fail(*power, "ambiguous " + quote(power->text) + " after " + quote(token.text) +
                             ": write 1/" + std::string(function.name) +
                             "(...) or the inverse function");
    }
    Token open = lexer_.take();
    if (open.kind != TokenKind::LeftParen) fail(open, "expected '(' after " + quote(token.text));
    std::vector<Slot> args = arguments(open);
    bool too_many = function.max_args >= 0 && static_cast<int>(args.size()) > function.max_args;
    if (static_cast<int>(args.size()) < function.min_args || too_many)
        fail(token, arity_message(function, args.size()));
    Slot result = checked(emit_call(builder_, function, args));
    if (power) result = emit_power(builder_, result, builder_.constant(power->number));
    return result;
}

std::vector<Slot> Parser::arguments(const Token& open) {
    Nesting nesting(*this, open);
    int outer_bars = open_bars_;
    open_bars_ = 0;
    std::vector<Slot> args;
    if (lexer_.peek().kind == TokenKind::RightParen) {
        lexer_.take();
    } else {
        args.push_back(expression(0));
        while (lexer_.peek().kind == TokenKind::Comma) {
            lexer_.take();
            args.push_back(expression(0));
        }
        close(TokenKind::RightParen, open);
    }
    open_bars_ = outer_bars;
    return args;
}

}  // namespace

std::optional<CompileError> parse_equation(std::string_view source, const CompileLimits& limits,
                                           TapeBuilder& builder, Slot& output) {
    try {
        Parser parser(source, limits, builder);
        output = parser.equation();
        return std::nullopt;
    } catch (const ParseFailure& failure) {
        return failure.error;
    }
}

}  // namespace isomesh::expr
