// TapeBuilder: constant folding and common-subexpression elimination by hash-consing, the
// classic value-numbering scheme (Cocke 1970; see also "Engineering a Compiler", Cooper & Torczon,
// section 8.4.1), applied as each instruction is emitted so no separate pass is needed.
#include "tape/tape.h"

#include <array>
#include <bit>
#include <cassert>
#include <cmath>
#include <sstream>

#include "tape/op_math.h"

namespace isomesh {

namespace {

struct OpInfo {
    std::string_view name;
    int arity;
    bool commutes;
};

constexpr std::array<OpInfo, kOpCount> kOpInfo = {{
    {"const", 0, false}, {"var-x", 0, false}, {"var-y", 0, false}, {"var-z", 0, false},
    {"param", 0, false}, {"neg", 1, false},   {"square", 1, false}, {"powi", 1, false},
    {"sqrt", 1, false},  {"cbrt", 1, false},  {"abs", 1, false},    {"sgn", 1, false},
    {"floor", 1, false}, {"ceil", 1, false},  {"round", 1, false},  {"exp", 1, false},
    {"ln", 1, false},    {"lg", 1, false},    {"ld", 1, false},     {"sin", 1, false},
    {"cos", 1, false},   {"tan", 1, false},   {"asin", 1, false},   {"acos", 1, false},
    {"atan", 1, false},  {"sinh", 1, false},  {"cosh", 1, false},   {"tanh", 1, false},
    {"add", 2, true},    {"sub", 2, false},   {"mul", 2, true},     {"div", 2, false},
    {"pow", 2, false},   {"atan2", 2, false}, {"min", 2, true},     {"max", 2, true},
    {"logsumexp", 2, true}, {"hypot", 2, true},
}};

const OpInfo& info(Op op) { return kOpInfo[static_cast<std::size_t>(op)]; }

bool is_constant_equal(const Instruction& i, double value) {
    return i.op == Op::Const && i.imm == value;
}

}  // namespace

int op_arity(Op op) { return info(op).arity; }
std::string_view op_name(Op op) { return info(op).name; }
bool op_commutes(Op op) { return info(op).commutes; }

unsigned Tape::variables_used() const {
    unsigned used = 0;
    for (const Instruction& i : code) {
        if (i.op == Op::VarX) used |= 1u;
        if (i.op == Op::VarY) used |= 2u;
        if (i.op == Op::VarZ) used |= 4u;
    }
    return used;
}

std::string Tape::validate() const {
    if (code.empty()) return "empty tape";
    for (std::size_t n = 0; n < code.size(); ++n) {
        const Instruction& i = code[n];
        if (static_cast<int>(i.op) >= kOpCount) return "bad opcode at " + std::to_string(n);
        int arity = op_arity(i.op);
        if ((arity >= 1 && i.a >= n) || (arity == 2 && i.b >= n))
            return "operand not before its use at " + std::to_string(n);
        if (i.op == Op::Param && !(i.imm >= 0 && i.imm < static_cast<double>(params.size())))
            return "bad parameter index at " + std::to_string(n);
    }
    return {};
}

std::string Tape::dump() const {
    std::ostringstream out;
    out.precision(17);
    for (std::size_t n = 0; n < code.size(); ++n) {
        const Instruction& i = code[n];
        out << '_' << n << " = " << op_name(i.op);
        int arity = op_arity(i.op);
        if (arity >= 1) out << " _" << i.a;
        if (arity == 2) out << " _" << i.b;
        if (i.op == Op::Const || i.op == Op::PowInt) out << ' ' << i.imm;
        if (i.op == Op::Param) out << ' ' << params[static_cast<std::size_t>(i.imm)];
        out << '\n';
    }
    return out.str();
}

std::size_t TapeBuilder::KeyHash::operator()(const Key& k) const {
    std::uint64_t h = static_cast<std::uint64_t>(k.op);
    for (std::uint64_t v : {std::uint64_t{k.a}, std::uint64_t{k.b}, k.imm_bits}) {
        h ^= v + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
    }
    return static_cast<std::size_t>(h);
}

std::uint32_t TapeBuilder::emit(Instruction instruction) {
    if (op_commutes(instruction.op) && instruction.a > instruction.b)
        std::swap(instruction.a, instruction.b);
    Key key{instruction.op, instruction.a, instruction.b, std::bit_cast<std::uint64_t>(instruction.imm)};
    auto [it, inserted] = index_.try_emplace(key, static_cast<std::uint32_t>(code_.size()));
    if (inserted) code_.push_back(instruction);
    return it->second;
}

std::uint32_t TapeBuilder::constant(double value) {
    if (value == 0.0) value = 0.0;  // one zero: -0 and +0 fold alike in every operation we emit
    return emit({Op::Const, 0, 0, value});
}

std::uint32_t TapeBuilder::var(int axis) {
    assert(axis >= 0 && axis < 3);
    static constexpr Op kVars[3] = {Op::VarX, Op::VarY, Op::VarZ};
    return emit({kVars[axis], 0, 0, 0.0});
}

std::uint32_t TapeBuilder::param(std::string_view name) {
    std::size_t index = 0;
    while (index < params_.size() && params_[index] != name) ++index;
    if (index == params_.size()) params_.emplace_back(name);
    return emit({Op::Param, 0, 0, static_cast<double>(index)});
}

std::uint32_t TapeBuilder::unary(Op op, std::uint32_t a) {
    assert(op_arity(op) == 1 && op != Op::PowInt && a < code_.size());
    const Instruction& operand = code_[a];
    if (operand.op == Op::Const) return constant(apply_unary(op, operand.imm, 0.0));
    if (op == Op::Neg && operand.op == Op::Neg) return operand.a;
    if (op == Op::Ln) {
        if (auto fused = log_of_exponential_sum(a)) return *fused;
    }
    if (op == Op::Sqrt) {
        if (auto fused = norm_of_square_sum(a)) return *fused;
    }
    return emit({op, a, 0, 0.0});
}

std::vector<std::uint32_t> TapeBuilder::sum_terms(std::uint32_t sum) const {
    std::vector<std::uint32_t> terms, pending{sum};  // an explicit stack: sums may nest deeply
    while (!pending.empty()) {
        const std::uint32_t slot = pending.back();
        pending.pop_back();
        if (code_[slot].op == Op::Add) {
            pending.push_back(code_[slot].b);
            pending.push_back(code_[slot].a);
        } else {
            terms.push_back(slot);
        }
    }
    return terms;
}

std::optional<std::uint32_t> TapeBuilder::log_of_exponential_sum(std::uint32_t sum) {
    if (code_[sum].op != Op::Add) return std::nullopt;
    std::vector<std::uint32_t> exponents;
    for (std::uint32_t slot : sum_terms(sum)) {
        const Instruction term = code_[slot];
        if (term.op == Op::Exp) {
            exponents.push_back(term.a);
        } else if (term.op == Op::Const && term.imm > 0.0 && std::isfinite(term.imm)) {
            exponents.push_back(constant(std::log(term.imm)));
        } else {
            return std::nullopt;
        }
    }
    std::uint32_t result = exponents[0];
    for (std::size_t i = 1; i < exponents.size(); ++i)
        result = binary(Op::LogSumExp, result, exponents[i]);
    return result;
}

std::optional<std::uint32_t> TapeBuilder::norm_of_square_sum(std::uint32_t sum) {
    if (code_[sum].op != Op::Add) return std::nullopt;
    const std::vector<std::uint32_t> terms = sum_terms(sum);
    for (std::uint32_t slot : terms)
        if (code_[slot].op != Op::Square) return std::nullopt;
    std::uint32_t result = code_[terms[0]].a;
    for (std::size_t i = 1; i < terms.size(); ++i)
        result = binary(Op::Hypot, result, code_[terms[i]].a);
    return result;
}

std::uint32_t TapeBuilder::pow_int(std::uint32_t a, int n) {
    assert(a < code_.size());
    if (code_[a].op == Op::Const) return constant(isomesh::pow_int(code_[a].imm, n));
    if (n == 1) return a;
    if (n == 2) return emit({Op::Square, a, 0, 0.0});
    return emit({Op::PowInt, a, 0, static_cast<double>(n)});
}

std::uint32_t TapeBuilder::binary(Op op, std::uint32_t a, std::uint32_t b) {
    assert(op_arity(op) == 2 && a < code_.size() && b < code_.size());
    const Instruction& left = code_[a];
    const Instruction& right = code_[b];
    if (left.op == Op::Const && right.op == Op::Const)
        return constant(apply_binary(op, left.imm, right.imm));
    switch (op) {
        case Op::Add:
            if (is_constant_equal(right, 0.0)) return a;
            if (is_constant_equal(left, 0.0)) return b;
            break;
        case Op::Sub:
            if (is_constant_equal(right, 0.0)) return a;
            if (is_constant_equal(left, 0.0)) return unary(Op::Neg, b);
            break;
        case Op::Mul:
            if (is_constant_equal(right, 1.0)) return a;
            if (is_constant_equal(left, 1.0)) return b;
            if (is_constant_equal(right, -1.0)) return unary(Op::Neg, a);
            if (is_constant_equal(left, -1.0)) return unary(Op::Neg, b);
            if (a == b) return emit({Op::Square, a, 0, 0.0});
            break;
        case Op::Div:
            if (is_constant_equal(right, 1.0)) return a;
            break;
        case Op::Pow:
            if (right.op == Op::Const && std::abs(right.imm) <= 64 &&
                right.imm == std::trunc(right.imm))
                return pow_int(a, static_cast<int>(right.imm));
            break;
        case Op::Min:
        case Op::Max:
            if (a == b) return a;
            break;
        default: break;
    }
    return emit({op, a, b, 0.0});
}

Tape TapeBuilder::finish(std::uint32_t output) const {
    assert(output < code_.size());
    std::vector<bool> live(code_.size(), false);
    live[output] = true;
    for (std::size_t n = output + 1; n-- > 0;) {
        if (!live[n]) continue;
        int arity = op_arity(code_[n].op);
        if (arity >= 1) live[code_[n].a] = true;
        if (arity == 2) live[code_[n].b] = true;
    }
    Tape tape;
    tape.params = params_;
    std::vector<std::uint32_t> renumber(code_.size(), 0);
    for (std::size_t n = 0; n <= output; ++n) {
        if (!live[n]) continue;
        Instruction i = code_[n];
        i.a = renumber[i.a];
        i.b = renumber[i.b];
        renumber[n] = static_cast<std::uint32_t>(tape.code.size());
        tape.code.push_back(i);
    }
    assert(tape.validate().empty());
    return tape;
}

}  // namespace isomesh
