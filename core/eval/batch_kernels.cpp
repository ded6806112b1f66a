// The batch evaluator's loops. Each is a plain array loop over restrict pointers that computes the
// scalar semantics of op_math.h with a compile-time operation, so its values are bit-identical to
// the point evaluator's while the compiler vectorizes the arithmetic.
//
// Checked with -fopt-info-vec-optimized (GCC 12, -O3, x86-64): the loops of neg, square, sqrt,
// abs, add, sub, mul, div, min and max, in every operand form, report "loop vectorized using 16
// byte vectors" (and 32 byte vectors in the AVX2 clones); libm functions (sin, exp, ...) remain
// scalar calls. min and max vectorize only with -fno-trapping-math (their NaN tests must be
// if-converted) and sqrt only with -fno-math-errno; core/CMakeLists.txt sets both for isomesh_eval.
// Neither changes any result.
//
// On x86-64 with GCC, every loop is also compiled for AVX2 and picked at load time
// (target_clones): AVX2 without FMA rounds exactly as SSE2 does, so results do not depend on the
// machine.
#include "eval/batch_kernels.h"

#include <cassert>
#include <cmath>

#include "eval/tape_ops.h"
#include "tape/op_math.h"

namespace isomesh {

namespace {

/// apply_binary(op, a, b), with min and max spelled so that they vectorize in a few instructions
/// (one unordered test rather than two NaN tests joined by ||, which costs over twice as much):
/// the same values, NaN as a + b when either operand is NaN.
template <Op op>
inline double batch_binary(double a, double b) {
    if constexpr (op == Op::Min || op == Op::Max) {
        double chosen = op == Op::Min ? (a < b ? a : b) : (a > b ? a : b);
        return std::isunordered(a, b) ? a + b : chosen;
    } else {
        return apply_binary(op, a, b);
    }
}

// The loops, inlined into run_batch_steps (and so compiled for each of its target clones).
#define ISOMESH_LOOP [[gnu::always_inline]] inline void

ISOMESH_LOOP fill(double imm, double* __restrict out, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) out[i] = imm;
}

ISOMESH_LOOP copy(const double* __restrict a, double* __restrict out, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) out[i] = a[i];
}

template <Op op>
ISOMESH_LOOP unary_loop(const double* __restrict a, double imm, double* __restrict out,
                        std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) out[i] = apply_unary(op, a[i], imm);
}

template <Op op>
ISOMESH_LOOP binary_loop(const double* __restrict a, const double* __restrict b,
                         double* __restrict out, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) out[i] = batch_binary<op>(a[i], b[i]);
}

template <Op op>
ISOMESH_LOOP immediate_a_loop(double imm, const double* __restrict b, double* __restrict out,
                              std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) out[i] = batch_binary<op>(imm, b[i]);
}

template <Op op>
ISOMESH_LOOP immediate_b_loop(const double* __restrict a, double imm, double* __restrict out,
                              std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) out[i] = batch_binary<op>(a[i], imm);
}

#undef ISOMESH_LOOP

constexpr int case_of(Op op, BatchForm form) {
    return static_cast<int>(op) * 3 + static_cast<int>(form);
}

// Every unary and binary operation, for the switch below.
#define ISOMESH_UNARY_OPS(X)                                                                 \
    X(Neg)                                                                                   \
    X(Square) X(PowInt) X(Sqrt) X(Cbrt) X(Abs) X(Sgn) X(Floor) X(Ceil) X(Round) X(Exp) X(Ln) \
        X(Log10) X(Log2) X(Sin) X(Cos) X(Tan) X(Asin) X(Acos) X(Atan) X(Sinh) X(Cosh) X(Tanh)
#define ISOMESH_BINARY_OPS(X) X(Add) X(Sub) X(Mul) X(Div) X(Pow) X(Atan2) X(Min) X(Max)
#define ISOMESH_COUNT(name) +1
static_assert(5 ISOMESH_UNARY_OPS(ISOMESH_COUNT) ISOMESH_BINARY_OPS(ISOMESH_COUNT) == kOpCount,
              "the lists must name every operation");
#undef ISOMESH_COUNT

}  // namespace

ISOMESH_VECTOR_CLONES void run_batch_steps(std::span<const BatchStep> steps,
                                           const double* const* read, double* const* write,
                                           std::size_t n) {
    assert(n <= kBatchBlock);
    for (const BatchStep& s : steps) {
        const double* a = read[s.a];
        const double* b = read[s.b];
        double* out = write[s.out];
        switch (case_of(s.op, s.form)) {
            case case_of(Op::Const, BatchForm::Registers):
                fill(s.imm, out, n);
                break;
            case case_of(Op::VarX, BatchForm::Registers):
            case case_of(Op::VarY, BatchForm::Registers):
            case case_of(Op::VarZ, BatchForm::Registers):
                copy(a, out, n);
                break;
#define ISOMESH_UNARY_CASE(name)                  \
    case case_of(Op::name, BatchForm::Registers): \
        unary_loop<Op::name>(a, s.imm, out, n);   \
        break;
                ISOMESH_UNARY_OPS(ISOMESH_UNARY_CASE)
#undef ISOMESH_UNARY_CASE
#define ISOMESH_BINARY_CASE(name)                     \
    case case_of(Op::name, BatchForm::Registers):     \
        binary_loop<Op::name>(a, b, out, n);          \
        break;                                        \
    case case_of(Op::name, BatchForm::ImmediateA):    \
        immediate_a_loop<Op::name>(s.imm, b, out, n); \
        break;                                        \
    case case_of(Op::name, BatchForm::ImmediateB):    \
        immediate_b_loop<Op::name>(a, s.imm, out, n); \
        break;
                ISOMESH_BINARY_OPS(ISOMESH_BINARY_CASE)
#undef ISOMESH_BINARY_CASE
            default:
                assert(!"no such batch step");
        }
    }
}

}  // namespace isomesh
