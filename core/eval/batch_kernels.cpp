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
#include <type_traits>

#include "eval/step_dispatch.h"
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

// The loops, inlined into run_batch_steps (and so compiled for each of its target clones) and
// run_point_steps (one point: Count is std::integral_constant<std::size_t, 1>).
#define ISOMESH_LOOP [[gnu::always_inline]] inline void

template <class Count>
ISOMESH_LOOP fill(double imm, double* __restrict out, Count n) {
    for (std::size_t i = 0; i < n; ++i) out[i] = imm;
}

template <class Count>
ISOMESH_LOOP copy(const double* __restrict a, double* __restrict out, Count n) {
    for (std::size_t i = 0; i < n; ++i) out[i] = a[i];
}

template <Op op, class Count>
ISOMESH_LOOP unary_loop(const double* __restrict a, double imm, double* __restrict out, Count n) {
    for (std::size_t i = 0; i < n; ++i) out[i] = apply_unary(op, a[i], imm);
}

template <Op op, class Count>
ISOMESH_LOOP binary_loop(const double* __restrict a, const double* __restrict b,
                         double* __restrict out, Count n) {
    for (std::size_t i = 0; i < n; ++i) out[i] = batch_binary<op>(a[i], b[i]);
}

template <Op op, class Count>
ISOMESH_LOOP immediate_a_loop(double imm, const double* __restrict b, double* __restrict out,
                              Count n) {
    for (std::size_t i = 0; i < n; ++i) out[i] = batch_binary<op>(imm, b[i]);
}

template <Op op, class Count>
ISOMESH_LOOP immediate_b_loop(const double* __restrict a, double imm, double* __restrict out,
                              Count n) {
    for (std::size_t i = 0; i < n; ++i) out[i] = batch_binary<op>(a[i], imm);
}

#undef ISOMESH_LOOP

/// The loops of one step over n points (n a std::integral_constant for a single point or a small
/// batch).
template <class Count>
struct StepLoops {
    const BatchStep& s;
    const double* a;
    const double* b;
    double* out;
    Count n;

    void constant() { fill(s.imm, out, n); }
    void variable() { copy(a, out, n); }
    template <Op op>
    void unary() {
        unary_loop<op>(a, s.imm, out, n);
    }
    template <Op op, BatchForm form>
    void binary() {
        if constexpr (form == BatchForm::Registers)
            binary_loop<op>(a, b, out, n);
        else if constexpr (form == BatchForm::ImmediateA)
            immediate_a_loop<op>(s.imm, b, out, n);
        else
            immediate_b_loop<op>(a, s.imm, out, n);
    }
};

template <class Count>
[[gnu::always_inline]] inline void run_steps(std::span<const BatchStep> steps,
                                             const double* const* read, double* const* write,
                                             Count n) {
    for (const BatchStep& s : steps) {
        StepLoops<Count> loops{s, read[s.a], read[s.b], write[s.out], n};
        dispatch_step(s, loops);
    }
}

}  // namespace

ISOMESH_VECTOR_CLONES void run_batch_steps(std::span<const BatchStep> steps,
                                           const double* const* read, double* const* write,
                                           std::size_t n) {
    assert(n <= kBatchBlock);
    run_steps(steps, read, write, n);
}

ISOMESH_VECTOR_CLONES void run_small_batch_steps(std::span<const BatchStep> steps,
                                                 const double* const* read, double* const* write) {
    run_steps(steps, read, write, std::integral_constant<std::size_t, kSmallBatch>{});
}

void run_point_steps(std::span<const BatchStep> steps, double* registers) {
    double* r = registers;
    for (const BatchStep& s : steps) {
        // Immediates by selection rather than by a case per operand form: a third of the cases
        // for the one indirect jump, which mispredicts less.
        const double a = *(s.form == BatchForm::ImmediateA ? &s.imm : r + s.a);
        const double b = *(s.form == BatchForm::ImmediateB ? &s.imm : r + s.b);
        double v;
        switch (s.op) {
            case Op::Const:
                v = s.imm;
                break;
            case Op::VarX:
            case Op::VarY:
            case Op::VarZ:
                v = a;
                break;
#define ISOMESH_UNARY_CASE(name)             \
    case Op::name:                           \
        v = apply_unary(Op::name, a, s.imm); \
        break;
                ISOMESH_UNARY_OPS(ISOMESH_UNARY_CASE)
#undef ISOMESH_UNARY_CASE
#define ISOMESH_BINARY_CASE(name)         \
    case Op::name:                        \
        v = apply_binary(Op::name, a, b); \
        break;
                ISOMESH_BINARY_OPS(ISOMESH_BINARY_CASE)
#undef ISOMESH_BINARY_CASE
            default:
                v = 0.0;
                assert(!"no such step");
        }
        r[s.out] = v;
    }
}

}  // namespace isomesh
