#include "expr/vm_reader.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <span>
#include <unordered_map>
#include <vector>

#include "expr/functions.h"
#include "expr/utf8.h"

namespace isomesh {

namespace {

using expr::quote;
using expr::Slot;

struct Word {
    std::string_view text;
    int column;  // 1-based
};

struct VmFailure {
    CompileError error;
};

/// The fields of one line, comment removed.
std::vector<Word> split_words(std::string_view line) {
    std::vector<Word> words;
    std::size_t end = line.find('#');
    if (end != std::string_view::npos) line = line.substr(0, end);
    std::size_t pos = 0;
    while (true) {
        pos = line.find_first_not_of(" \t\r\v\f", pos);
        if (pos == std::string_view::npos) break;
        std::size_t stop = std::min(line.find_first_of(" \t\r\v\f", pos), line.size());
        words.push_back({line.substr(pos, stop - pos), static_cast<int>(pos) + 1});
        pos = stop;
    }
    return words;
}

/// The tape operation named `name` taking `operands` operands (our op names, plus Fidget's
/// two-operand `atan`), or false. powi, logsumexp and hypot are the compiler's own operations,
/// not opcodes of the format.
bool find_operation(std::string_view name, std::size_t operands, Op& op) {
    if (name == "atan" && operands == 2) {
        op = Op::Atan2;
        return true;
    }
    for (int k = static_cast<int>(Op::Neg); k < kOpCount; ++k) {
        auto candidate = static_cast<Op>(k);
        if (candidate != Op::PowInt && candidate != Op::LogSumExp && candidate != Op::Hypot &&
            op_name(candidate) == name) {
            op = candidate;
            return true;
        }
    }
    return false;
}

class VmReader {
  public:
    explicit VmReader(const CompileLimits& limits) : limits_(limits) {}

    Slot read(std::string_view text);
    TapeBuilder& builder() { return builder_; }

  private:
    void read_line(std::string_view line);
    Slot instruction(const std::vector<Word>& words);
    Slot leaf(const Word& opcode, std::span<const Word> operands);
    Slot operation(const Word& opcode, std::span<const Word> operands);
    Slot operand(const Word& word) const;
    double number(const Word& word) const;
    void expect_operands(const Word& opcode, std::span<const Word> operands, std::size_t n) const;
    [[noreturn]] void fail(std::string message, int column = 0) const;

    const CompileLimits& limits_;
    TapeBuilder builder_;
    struct Definition {
        Slot slot;
        int line;
    };
    std::unordered_map<std::string_view, Definition> names_;
    int line_ = 0;
    std::size_t instructions_ = 0;
    Slot last_ = 0;
};

void VmReader::fail(std::string message, int column) const {
    throw VmFailure{CompileError{std::move(message), line_, column, true}};
}

Slot VmReader::read(std::string_view text) {
    std::size_t pos = 0;
    while (pos < text.size()) {
        std::size_t end = std::min(text.find('\n', pos), text.size());
        ++line_;
        read_line(text.substr(pos, end - pos));
        pos = end + 1;
    }
    if (instructions_ == 0) fail("no instructions");
    return last_;
}

void VmReader::read_line(std::string_view line) {
    std::vector<Word> words = split_words(line);
    if (words.empty()) return;
    if (++instructions_ > limits_.max_instructions)
        fail("more than " + std::to_string(limits_.max_instructions) + " instructions");
    const Word& name = words[0];
    if (words.size() < 2) fail("missing opcode after " + quote(name.text), name.column);
    auto [it, inserted] = names_.try_emplace(name.text, Definition{0, line_});
    if (!inserted) {
        fail(quote(name.text) + " already defined at line " + std::to_string(it->second.line),
             name.column);
    }
    last_ = instruction(words);
    it->second.slot = last_;
}

Slot VmReader::instruction(const std::vector<Word>& words) {
    const Word& opcode = words[1];
    std::span<const Word> operands(words.begin() + 2, words.end());
    std::string_view op = opcode.text;
    if (op == "var-x" || op == "var-y" || op == "var-z" || op == "const")
        return leaf(opcode, operands);
    return operation(opcode, operands);
}

Slot VmReader::leaf(const Word& opcode, std::span<const Word> operands) {
    if (opcode.text == "const") {
        expect_operands(opcode, operands, 1);
        return builder_.constant(number(operands[0]));
    }
    expect_operands(opcode, operands, 0);
    return builder_.var(opcode.text.back() - 'x');
}

Slot VmReader::operation(const Word& opcode, std::span<const Word> operands) {
    if (opcode.text == "recip") {
        expect_operands(opcode, operands, 1);
        return builder_.binary(Op::Div, builder_.constant(1.0), operand(operands[0]));
    }
    Op op{};
    if (!find_operation(opcode.text, operands.size(), op))
        fail("unknown opcode " + quote(opcode.text), opcode.column);
    expect_operands(opcode, operands, static_cast<std::size_t>(op_arity(op)));
    Slot a = operand(operands[0]);
    if (op_arity(op) == 1) return builder_.unary(op, a);
    Slot b = operand(operands[1]);
    return builder_.binary(op, a, b);
}

void VmReader::expect_operands(const Word& opcode, std::span<const Word> operands,
                               std::size_t n) const {
    if (operands.size() == n) return;
    fail(quote(opcode.text) + " takes " + std::to_string(n) + " operand" + (n == 1 ? "" : "s") +
             ", got " + std::to_string(operands.size()),
         opcode.column);
}

Slot VmReader::operand(const Word& word) const {
    auto it = names_.find(word.text);
    // A name is defined once its line is complete: `_a add _a _b` on its own line is undefined.
    if (it == names_.end() || it->second.line == line_)
        fail("undefined name " + quote(word.text), word.column);
    return it->second.slot;
}

double VmReader::number(const Word& word) const {
    std::string_view text = word.text;
    if (text.size() > 1 && text[0] == '+' && text[1] != '-') text.remove_prefix(1);
    double value = 0.0;
    auto [end, status] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (status != std::errc{} || end != text.data() + text.size() || !std::isfinite(value))
        fail("bad number " + quote(word.text), word.column);
    return value;
}

}  // namespace

CompileResult read_vm(std::string_view text, const CompileLimits& limits) {
    CompileResult result;
    if (text.size() > limits.max_vm_bytes) {
        result.error =
            CompileError{"file too large: " + std::to_string(text.size()) +
                             " bytes, the limit is " + std::to_string(limits.max_vm_bytes),
                         1, 0, false};
        return result;
    }
    VmReader reader(limits);
    try {
        Slot output = reader.read(text);
        result.tape = reader.builder().finish(output);
    } catch (const VmFailure& failure) {
        result.error = failure.error;
    }
    return result;
}

}  // namespace isomesh
