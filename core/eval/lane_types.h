// Lane types for the kernels (interval_lanes.h, point_kernels.cpp): the same formulas run on
// one double or on a vector of kChunk doubles (GCC and clang vector extensions), whose mask type
// (the result of comparing two lane values) selects lane by lane with `m ? a : b`. Internal to the
// kernels' source files, inside their anonymous namespaces' reach only.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>

#include "eval/step_dispatch.h"

// Vectors are passed between inlined functions of the kernels' files only: no ABI is involved.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace isomesh::lanes {

#define ISOMESH_KERNEL [[gnu::always_inline]] inline
#define ISOMESH_MEMBER [[gnu::always_inline]]

template <std::size_t W>
struct LaneTypes;

template <>
struct LaneTypes<1> {
    using D = double;
    using M = std::int64_t;
    ISOMESH_MEMBER static D splat(double c) { return c; }
    ISOMESH_MEMBER static M splat_mask(std::int64_t c) { return c; }
};

/// Lanes computed together: one AVX2 register of doubles (two SSE2 registers in the default
/// build). Wider batches are computed chunk by chunk: wider vectors spill.
constexpr std::size_t kChunk = 4;

template <>
struct LaneTypes<kChunk> {
    typedef double D __attribute__((vector_size(8 * kChunk)));
    typedef std::int64_t M __attribute__((vector_size(8 * kChunk)));
    ISOMESH_MEMBER static D splat(double c) { return D{c, c, c, c}; }
    ISOMESH_MEMBER static M splat_mask(std::int64_t c) { return M{c, c, c, c}; }
};

/// The lanes of a register's array from `p` on, as a lane value.
template <class T, class U>
ISOMESH_KERNEL T load(const U* p) {
    T v;
    std::memcpy(&v, p, sizeof v);
    return v;
}

template <class T, class U>
ISOMESH_KERNEL void store(U* p, const T& v) {
    std::memcpy(p, &v, sizeof v);
}

/// Lane l of a lane value.
template <class T>
ISOMESH_KERNEL auto lane(const T& v, std::size_t l) {
    if constexpr (std::is_arithmetic_v<T>)
        return (void)l, v;
    else
        return v[l];
}

/// A mask as the integer mask type, all bits set in a true lane as vector comparisons give (a
/// scalar comparison gives a bool).
template <class M, class Mask>
ISOMESH_KERNEL M as_mask(const Mask& m) {
    if constexpr (std::is_arithmetic_v<M>)
        return m ? M(-1) : M(0);
    else
        return m;
}

/// Whether any lane of a mask is set.
template <class M>
ISOMESH_KERNEL bool any(const M& m) {
    if constexpr (std::is_arithmetic_v<M>) {
        return m != 0;
    } else {
        std::int64_t lanes[sizeof m / sizeof(std::int64_t)];
        std::memcpy(lanes, &m, sizeof m);
        std::int64_t all = 0;
        for (std::int64_t x : lanes) all |= x;
        return all != 0;
    }
}

/// A comparison's result as a mask that combines with | and &: a vector comparison gives one
/// already, a scalar one's bool becomes an integer (-1 or 0).
template <class Mask>
ISOMESH_KERNEL auto mask_of(const Mask& m) {
    if constexpr (std::is_same_v<Mask, bool>)
        return m ? std::int64_t(-1) : std::int64_t(0);
    else
        return m;
}

/// Lanes whose value is infinite or NaN.
template <class D>
ISOMESH_KERNEL auto nonfinite(const D& x) {
    return mask_of(x - x != D{});
}

/// A visitor of dispatch_step that runs a step on each of kChunks chunks of lanes: make(c) gives
/// chunk c's visitor.
template <std::size_t kChunks, class MakeStep>
struct Chunked {
    const MakeStep& make;

    ISOMESH_MEMBER void constant() {
        for (std::size_t c = 0; c < kChunks; ++c) make(c).constant();
    }
    ISOMESH_MEMBER void variable() {
        for (std::size_t c = 0; c < kChunks; ++c) make(c).variable();
    }
    template <Op op>
    ISOMESH_MEMBER void unary() {
        for (std::size_t c = 0; c < kChunks; ++c) make(c).template unary<op>();
    }
    template <Op op, BatchForm form>
    ISOMESH_MEMBER void binary() {
        for (std::size_t c = 0; c < kChunks; ++c) make(c).template binary<op, form>();
    }
};

}  // namespace isomesh::lanes
