// The instruction tape: the compiled form of every function isomesh meshes.
//
// A tape is a straight-line program in static single assignment form: instruction i computes slot i
// from slots with smaller indices, and the last instruction is the function's value. Expressions
// typed by people (expr/) and Fidget's .vm models both compile to it through TapeBuilder, which
// folds constants and shares common subexpressions as the tape is written, so every evaluator
// (eval/) sees the same short program.
//
// Parameters (slider values such as `a`) are leaves whose values are supplied at evaluation time,
// never folded: changing them needs no recompilation.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace isomesh {

enum class Op : std::uint8_t {
    // Leaves.
    Const,  // imm = the value
    VarX,
    VarY,
    VarZ,
    Param,  // imm = index into Tape::params
    // Unary: operand a.
    Neg,
    Square,
    PowInt,  // a ^ n with n = imm, a whole number (kept apart from Pow for exact signs and soundness)
    Sqrt,
    Cbrt,
    Abs,
    Sgn,
    Floor,
    Ceil,
    Round,
    Exp,
    Ln,
    Log10,
    Log2,
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Sinh,
    Cosh,
    Tanh,
    // Binary: operands a and b, a on the left.
    Add,
    Sub,
    Mul,
    Div,
    Pow,  // real power; NaN for a negative base unless b is whole (as std::pow)
    Atan2,  // atan2(a, b) = angle of the point (b, a)
    Min,
    Max,
    // ln(exp(a) + exp(b)), the smooth maximum (log-sum-exp) that smooth CSG blends are made of
    // (-ln(exp(-k a) + exp(-k b)) / k is a smooth min). Not an opcode of the languages:
    // TapeBuilder fuses the spelled-out form into it (see TapeBuilder::unary), so that every
    // evaluator sees one operation whose enclosures are tight (eval/interval_ranges.h).
    LogSumExp,
    // sqrt(a^2 + b^2), the Euclidean norm of (a, b). Not an opcode of the languages either:
    // TapeBuilder fuses sqrt of a sum of two or more squares into it (nested for more terms,
    // hypot(hypot(a, b), c)), so that every evaluator sees one operation whose value and gradient
    // enclosures are tight (the spelled-out a / sqrt(a^2 + b^2) counts a and the root as
    // unrelated: the dependency problem, worst on the distance terms of CAD models).
    Hypot,
};

inline constexpr int kOpCount = static_cast<int>(Op::Hypot) + 1;

/// Number of operands of `op`: 0 for leaves, 1 for unary, 2 for binary operations.
int op_arity(Op op);
/// A stable lower-case name for `op` (as used in dumps and the .vm format where one exists).
std::string_view op_name(Op op);
/// True for operations whose operands may be swapped (add, mul, min, max, logsumexp, hypot).
bool op_commutes(Op op);

struct Instruction {
    Op op = Op::Const;
    std::uint32_t a = 0;  // first operand: index of an earlier instruction (unary and binary ops)
    std::uint32_t b = 0;  // second operand (binary ops)
    double imm = 0.0;     // Const: value; PowInt: exponent; Param: parameter index
};

/// A compiled function. Invariants (checked by `validate`): non-empty; every operand index is
/// smaller than the index of the instruction using it; Param indices are < params.size().
/// The function's value is the value of the last instruction.
struct Tape {
    std::vector<Instruction> code;
    std::vector<std::string> params;  // parameter names, in first-use order

    std::uint32_t output() const { return static_cast<std::uint32_t>(code.size() - 1); }
    std::size_t size() const { return code.size(); }
    /// Which of x, y, z the function reads (bit 0 = x, 1 = y, 2 = z).
    unsigned variables_used() const;
    /// Empty when the invariants hold, else a description of the first violation.
    std::string validate() const;
    /// One instruction per line, `_i = op a b imm`, for debugging and golden tests.
    std::string dump() const;
};

/// Writes a tape instruction by instruction. Each call returns the slot holding the result.
/// Operations on constants are folded to constants (with the same IEEE semantics the point
/// evaluator uses); identical instructions are emitted once (hash-consing, which is common
/// subexpression elimination); a few identities are applied where they are exact for every
/// input, including infinities and NaN (x+0, x*1, x-0, x/1, --x, x^1, x^2 -> square(x)).
/// One rewrite is not an identity of IEEE arithmetic but a more accurate form of the same
/// function: ln(exp(a) + exp(b) + ...) (a sum of two or more exponentials, or of exponentials and
/// positive constants c = exp(ln c)) becomes logsumexp(logsumexp(a, b), ...), which agrees with it
/// within a few rounding errors where no exp overflows or underflows, and stays finite where one
/// does. Likewise sqrt(a^2 + b^2 + ...) (a sum of two or more squares) becomes
/// hypot(hypot(a, b), ...), which computes sqrt(sqrt(a^2 + b^2)^2 + c^2): the same value within
/// a few rounding errors, with the same overflow and underflow.
class TapeBuilder {
public:
    std::uint32_t constant(double value);
    std::uint32_t var(int axis);  // 0 = x, 1 = y, 2 = z
    /// The slot of parameter `name`, created on first use.
    std::uint32_t param(std::string_view name);
    std::uint32_t unary(Op op, std::uint32_t a);
    std::uint32_t binary(Op op, std::uint32_t a, std::uint32_t b);
    /// a ^ n for a whole exponent n.
    std::uint32_t pow_int(std::uint32_t a, int n);

    /// Instructions emitted so far (before dead-code elimination).
    std::size_t size() const { return code_.size(); }
    bool is_constant(std::uint32_t slot) const { return code_[slot].op == Op::Const; }
    double constant_value(std::uint32_t slot) const { return code_[slot].imm; }

    /// The tape computing slot `output`: unused instructions dropped, slots renumbered in order,
    /// `output` last. Parameters keep their names and first-use order even when unused, so a
    /// caller can always supply every named parameter.
    Tape finish(std::uint32_t output) const;

private:
    struct Key {
        Op op;
        std::uint32_t a, b;
        std::uint64_t imm_bits;
        bool operator==(const Key&) const = default;
    };
    struct KeyHash {
        std::size_t operator()(const Key& k) const;
    };

    std::uint32_t emit(Instruction instruction);
    /// logsumexp of the exponents when `sum` is a sum of two or more exponentials and positive
    /// constants (ln(sum) then), else nothing.
    std::optional<std::uint32_t> log_of_exponential_sum(std::uint32_t sum);
    /// hypot of the bases when `sum` is a sum of two or more squares (sqrt(sum) then), else
    /// nothing.
    std::optional<std::uint32_t> norm_of_square_sum(std::uint32_t sum);
    /// The terms of the sum `sum` (nested adds), left to right.
    std::vector<std::uint32_t> sum_terms(std::uint32_t sum) const;

    std::vector<Instruction> code_;
    std::vector<std::string> params_;
    std::unordered_map<Key, std::uint32_t, KeyHash> index_;
};

}  // namespace isomesh
