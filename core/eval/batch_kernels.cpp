// The batch evaluator's loops. Each is a plain array loop over restrict pointers that calls the
// scalar semantics of op_math.h with a compile-time operation, so its values are bit-identical to
// the point evaluator's while the compiler vectorizes the arithmetic.
//
// Checked with -fopt-info-vec-optimized (GCC 12, -O3, x86-64 SSE2): the loops of neg, square,
// sqrt, abs, add, sub, mul, div, min and max, in every operand form, report "loop vectorized using
// 16 byte vectors"; libm functions (sin, exp, ...) remain scalar calls. min and max vectorize only
// with -fno-trapping-math (their NaN tests must be if-converted) and sqrt only with
// -fno-math-errno; core/CMakeLists.txt sets both for isomesh_eval. Neither changes any result.
#include "eval/batch_kernels.h"

#include <array>
#include <cassert>
#include <utility>

#include "eval/tape_ops.h"
#include "tape/op_math.h"

namespace isomesh {

namespace {

void fill(const double*, const double*, double imm, double* __restrict out, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) out[i] = imm;
}

void copy(const double* __restrict a, const double*, double, double* __restrict out,
          std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) out[i] = a[i];
}

template <Op op>
void unary_loop(const double* __restrict a, const double*, double imm, double* __restrict out,
                std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) out[i] = apply_unary(op, a[i], imm);
}

template <Op op>
void binary_loop(const double* __restrict a, const double* __restrict b, double,
                 double* __restrict out, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) out[i] = apply_binary(op, a[i], b[i]);
}

template <Op op>
void binary_immediate_a(const double*, const double* __restrict b, double imm,
                        double* __restrict out, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) out[i] = apply_binary(op, imm, b[i]);
}

template <Op op>
void binary_immediate_b(const double* __restrict a, const double*, double imm,
                        double* __restrict out, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) out[i] = apply_binary(op, a[i], imm);
}

using KernelRow = std::array<BatchKernel, 3>;  // indexed by BatchForm

template <Op op>
constexpr KernelRow kernel_row() {
    if constexpr (is_leaf(op)) {
        BatchKernel leaf = op == Op::Const ? fill : copy;
        return {leaf, leaf, leaf};
    } else if constexpr (is_unary(op)) {
        return {unary_loop<op>, nullptr, nullptr};
    } else {
        return {binary_loop<op>, binary_immediate_a<op>, binary_immediate_b<op>};
    }
}

template <std::size_t... I>
constexpr std::array<KernelRow, kOpCount> kernel_table(std::index_sequence<I...>) {
    return {kernel_row<static_cast<Op>(I)>()...};
}

constexpr std::array<KernelRow, kOpCount> kKernels =
    kernel_table(std::make_index_sequence<kOpCount>());

}  // namespace

BatchKernel batch_kernel(Op op, BatchForm form) {
    BatchKernel kernel = kKernels[static_cast<std::size_t>(op)][static_cast<std::size_t>(form)];
    assert(kernel != nullptr);
    return kernel;
}

}  // namespace isomesh
