// The point-gradient kernels. The formulas are forward_mode.h's on double, written over lane types
// (lane_types.h); where a formula below differs in spelling, the comment says why it computes the
// same bits.
#include "eval/point_kernels.h"

#include "eval/forward_mode.h"
#include "eval/lane_types.h"
#include "tape/op_math.h"

namespace isomesh {

namespace {

using namespace lanes;

/// forward_mode::term(partial, d): exactly 0 for a zero tangent.
template <class D>
ISOMESH_KERNEL D term(const D& partial, const D& d) {
    return d == D{} ? D{} : partial * d;
}

/// term(1, d) and term(-1, d): 1 * d and -1 * d are d and -d exactly.
template <class D>
ISOMESH_KERNEL D term_one(const D& d) {
    return d == D{} ? D{} : d;
}
template <class D>
ISOMESH_KERNEL D term_minus_one(const D& d) {
    return d == D{} ? D{} : -d;
}

/// std::fabs in every lane.
template <class D>
ISOMESH_KERNEL D abs_lanes(const D& x) {
    return x < D{} ? -x : x;
}

/// pow_int(x, k) of op_math.h in every lane, for k >= 0: the same multiplications in order.
template <class D>
ISOMESH_KERNEL D pow_lanes(const D& x, unsigned k, const D& one) {
    D result = one, base = x;
    while (k != 0) {
        if (k & 1u) result *= base;
        base *= base;
        k >>= 1u;
    }
    return result;
}

/// V lanes of the register file, from lane `offset` on.
template <std::size_t V, std::size_t W>
struct Lanes {
    using D = typename LaneTypes<V>::D;
    PointRegister<W>* registers;
    std::size_t offset;

    ISOMESH_MEMBER D value(std::uint32_t r) const { return load<D>(registers[r].value + offset); }
    ISOMESH_MEMBER D grad(std::uint32_t r, int k) const {
        return load<D>(registers[r].grad[k] + offset);
    }
    ISOMESH_MEMBER void set_value(std::uint32_t r, const D& v) {
        store(registers[r].value + offset, v);
    }
    ISOMESH_MEMBER void set_grad(std::uint32_t r, int k, const D& g) {
        store(registers[r].grad[k] + offset, g);
    }
};

/// Per-lane values of the reference code, gathered into a lane value.
template <std::size_t V, class D, class F>
ISOMESH_KERNEL D each_lane(const F& f) {
    double out[V];
    for (std::size_t l = 0; l < V; ++l) out[l] = f(l);
    return load<D>(out);
}

/// One step over V lanes (a visitor of dispatch_step through Chunked).
template <std::size_t V, std::size_t W>
struct PointStep {
    using D = typename LaneTypes<V>::D;
    using L = LaneTypes<V>;
    const BatchStep& s;
    Lanes<V, W>& lanes;

    ISOMESH_MEMBER void constant() {
        lanes.set_value(s.out, L::splat(s.imm));
        for (int k = 0; k < 3; ++k) lanes.set_grad(s.out, k, D{});
    }

    ISOMESH_MEMBER void variable() {
        lanes.set_value(s.out, lanes.value(s.a));
        for (int k = 0; k < 3; ++k) lanes.set_grad(s.out, k, lanes.grad(s.a, k));
    }

    template <Op op>
    ISOMESH_MEMBER void unary() {
        const D a = lanes.value(s.a);
        D r, partial{};
        if constexpr (op == Op::Neg) {
            r = -a;
        } else if constexpr (op == Op::Square) {
            r = a * a;
            partial = L::splat(2.0) * a;
        } else {
            r = each_lane<V, D>([&](std::size_t l) { return apply_unary(op, lane(a, l), s.imm); });
            if constexpr (op == Op::Sqrt) {
                partial = L::splat(0.5) / r;
            } else if constexpr (op == Op::Exp) {
                partial = r;
            } else if constexpr (op == Op::Ln) {
                partial = L::splat(1.0) / a;
            } else if (op == Op::PowInt && s.imm > 0.0) {
                partial =
                    L::splat(s.imm) * pow_lanes(a, static_cast<unsigned>(s.imm) - 1, L::splat(1.0));
            } else {
                partial = each_lane<V, D>([&](std::size_t l) {
                    return forward_mode::unary_partial(op, lane(a, l), lane(r, l), s.imm);
                });
            }
        }
        lanes.set_value(s.out, r);
        for (int k = 0; k < 3; ++k) {
            const D d = lanes.grad(s.a, k);
            lanes.set_grad(s.out, k, op == Op::Neg ? term_minus_one(d) : term(partial, d));
        }
    }

    template <bool in_register>
    ISOMESH_MEMBER D operand(std::uint32_t r) const {
        if constexpr (in_register) return lanes.value(r);
        return L::splat(s.imm);
    }
    template <bool in_register>
    ISOMESH_MEMBER D operand_grad(std::uint32_t r, int k) const {
        if constexpr (in_register) return lanes.grad(r, k);
        return D{};
    }

    template <Op op, BatchForm form>
    ISOMESH_MEMBER void binary() {
        constexpr bool a_in_register = form != BatchForm::ImmediateA;
        constexpr bool b_in_register = form != BatchForm::ImmediateB;
        const D a = operand<a_in_register>(s.a), b = operand<b_in_register>(s.b);
        D r, da{}, db{};
        if constexpr (op == Op::Add) {
            r = a + b;
        } else if constexpr (op == Op::Sub) {
            r = a - b;
        } else if constexpr (op == Op::Mul) {
            r = a * b;
            da = b;
            db = a;
        } else if constexpr (op == Op::Div) {
            r = a / b;
            da = L::splat(1.0) / b;
            db = -(r / b);
        } else if constexpr (op == Op::Min || op == Op::Max) {
            // apply_binary: NaN as a + b when either operand is NaN, else a < b ? a : b.
            const D chosen = op == Op::Min ? (a < b ? a : b) : (a > b ? a : b);
            r = mask_of(a != a) | mask_of(b != b) ? a + b : chosen;
        } else if constexpr (op == Op::Hypot) {
            // forward_mode::norm_partials: a / r and b / r, 0 where r = 0.
            r = each_lane<V, D>(
                [&](std::size_t l) { return euclidean_norm(lane(a, l), lane(b, l)); });
            const auto kink = r == D{};
            da = kink ? D{} : a / r;
            db = kink ? D{} : b / r;
        } else if constexpr (op == Op::LogSumExp) {
            // forward_mode::step: an operand's gradient beyond the cutoff (pick), else the weights
            // (forward_mode::blend) as partial derivatives.
            r = each_lane<V, D>([&](std::size_t l) { return log_sum_exp(lane(a, l), lane(b, l)); });
            double pa[V], pb[V];
            for (std::size_t l = 0; l < V; ++l) {
                const auto w = forward_mode::log_sum_exp_weights(lane(a, l), lane(b, l));
                pa[l] = w.da;
                pb[l] = w.db;
            }
            da = load<D>(pa);
            db = load<D>(pb);
        } else {
            r = each_lane<V, D>(
                [&](std::size_t l) { return apply_binary(op, lane(a, l), lane(b, l)); });
            double pa[V], pb[V];
            for (std::size_t l = 0; l < V; ++l) {
                const auto p =
                    forward_mode::binary_partials(op, lane(a, l), lane(b, l), lane(r, l));
                pa[l] = p.da;
                pb[l] = p.db;
            }
            da = load<D>(pa);
            db = load<D>(pb);
        }
        lanes.set_value(s.out, r);
        for (int k = 0; k < 3; ++k) {
            const D ga = operand_grad<a_in_register>(s.a, k);
            const D gb = operand_grad<b_in_register>(s.b, k);
            D g;
            if constexpr (op == Op::Add)
                g = term_one(ga) + term_one(gb);
            else if constexpr (op == Op::Sub)
                g = term_one(ga) + term_minus_one(gb);
            else if constexpr (op == Op::Min)
                g = a < b ? ga : gb;  // forward_mode::pick at a point
            else if constexpr (op == Op::Max)
                g = a > b ? ga : gb;
            else if constexpr (op == Op::LogSumExp)  // one operand wins outright: pick it
                g = mask_of(abs_lanes(a - b) > L::splat(kLogSumExpCutoff))
                        ? (a > b ? ga : gb)
                        : term(da, ga) + term(db, gb);
            else
                g = term(da, ga) + term(db, gb);
            lanes.set_grad(s.out, k, g);
        }
    }
};

template <std::size_t W>
ISOMESH_KERNEL void run(std::span<const BatchStep> steps, PointRegister<W>* registers) {
    constexpr std::size_t V = W == 1 ? 1 : kChunk;
    constexpr std::size_t kChunks = W / V;
    static_assert(W % V == 0);
    Lanes<V, W> chunks[kChunks];
    for (std::size_t c = 0; c < kChunks; ++c) chunks[c] = {registers, c * V};
    for (const BatchStep& s : steps) {
        struct {
            const BatchStep& s;
            Lanes<V, W> (&chunks)[kChunks];
            ISOMESH_MEMBER PointStep<V, W> operator()(std::size_t c) const {
                return {s, chunks[c]};
            }
        } make{s, chunks};
        Chunked<kChunks, decltype(make)> visitor{make};
        dispatch_step(s, visitor);
    }
}

}  // namespace

void run_point_gradient_steps(std::span<const BatchStep> steps, PointRegister<1>* registers) {
    run(steps, registers);
}

ISOMESH_VECTOR_CLONES void run_point_gradient_steps(std::span<const BatchStep> steps,
                                                    PointRegister<kPointLanes>* registers) {
    run(steps, registers);
}

}  // namespace isomesh
