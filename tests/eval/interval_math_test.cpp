// Interval arithmetic operation by operation: soundness as a property over random operand
// intervals made of awkward endpoints (zeros of both signs, poles, infinities), and the flags and
// enclosures of the classic pole cases.
#include "eval/interval_math.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "eval/tape_ops.h"
#include "tape/op_math.h"

namespace isomesh {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = std::numbers::pi;

IntervalValue iv(double lo, double hi) {
    return {{lo, hi}, false, false};
}

/// Endpoints where operations change behaviour.
const std::vector<double>& awkward_values() {
    static const std::vector<double> values = {
        -kInf, -1e300, -710.0,  -100.0, -3 * kPi / 2, -kPi,   -3.0,  -2.0,  -kPi / 2,
        -1.0,  -0.5,   -1e-300, -0.0,   0.0,          1e-300, 0.5,   1.0,   kPi / 2,
        2.0,   2.5,    3.0,     kPi,    3 * kPi / 2,  100.0,  710.0, 1e300, kInf};
    return values;
}

/// A random operand interval: two awkward or random endpoints, sorted.
Interval random_interval(std::mt19937_64& rng) {
    const auto& awkward = awkward_values();
    std::uniform_real_distribution<double> u(-4.0, 4.0);
    auto endpoint = [&] { return rng() % 2 ? awkward[rng() % awkward.size()] : u(rng); };
    double a = endpoint(), b = rng() % 4 == 0 ? a : endpoint();
    return {std::min(a, b), std::max(a, b)};
}

/// Values in `i`: its ends, the awkward values inside, random ones.
std::vector<double> values_in(std::mt19937_64& rng, const Interval& i) {
    std::vector<double> values = {i.lo, i.hi};
    for (double v : awkward_values())
        if (i.contains(v)) values.push_back(v);
    for (int k = 0; k < 8; ++k) {
        double lo = std::max(i.lo, -1e6), hi = std::min(i.hi, 1e6);
        if (lo <= hi) values.push_back(std::uniform_real_distribution<double>(lo, hi)(rng));
    }
    // Neighbours of the ends, where libm rounding could step outside.
    for (double v : {std::nextafter(i.lo, kInf), std::nextafter(i.hi, -kInf)})
        if (i.contains(v)) values.push_back(v);
    return values;
}

bool encloses(const IntervalValue& r, double v) {
    return std::isnan(v) ? r.maybe_undefined : r.value.contains(v);
}

TEST(IntervalMath, unary_operations_are_sound_on_random_intervals) {
    std::mt19937_64 rng(11);
    for (int op_index = static_cast<int>(Op::Neg); op_index <= static_cast<int>(Op::Tanh);
         ++op_index) {
        Op op = static_cast<Op>(op_index);
        for (int n = 0; n < 3000; ++n) {
            Interval a = random_interval(rng);
            double imm =
                op == Op::PowInt ? static_cast<double>(static_cast<int>(rng() % 13) - 6) : 0.0;
            IntervalValue r = interval_unary(op, {a, false, false}, imm);
            for (double x : values_in(rng, a)) {
                double v = apply_unary(op, x, imm);
                ASSERT_TRUE(encloses(r, v))
                    << op_name(op) << " " << imm << " of [" << a.lo << ", " << a.hi << "] = ["
                    << r.value.lo << ", " << r.value.hi << "] undefined " << r.maybe_undefined
                    << " misses f(" << x << ") = " << v;
            }
        }
    }
}

TEST(IntervalMath, binary_operations_are_sound_on_random_intervals) {
    std::mt19937_64 rng(12);
    for (int op_index = static_cast<int>(Op::Add); op_index < kOpCount; ++op_index) {
        Op op = static_cast<Op>(op_index);
        for (int n = 0; n < 3000; ++n) {
            Interval a = random_interval(rng), b = random_interval(rng);
            IntervalValue r = interval_binary(op, {a, false, false}, {b, false, false});
            std::vector<double> xs = values_in(rng, a), ys = values_in(rng, b);
            for (double x : xs) {
                for (double y : ys) {
                    double v = apply_binary(op, x, y);
                    ASSERT_TRUE(encloses(r, v))
                        << op_name(op) << " of [" << a.lo << ", " << a.hi << "] x [" << b.lo << ", "
                        << b.hi << "] = [" << r.value.lo << ", " << r.value.hi << "] undefined "
                        << r.maybe_undefined << " misses f(" << x << ", " << y << ") = " << v;
                }
            }
        }
    }
}

TEST(IntervalMath, reciprocal_across_zero_is_entire_and_discontinuous) {
    IntervalValue r = interval_binary(Op::Div, iv(1, 1), iv(-1, 1));
    EXPECT_EQ(r.value.lo, -kInf);
    EXPECT_EQ(r.value.hi, kInf);
    EXPECT_TRUE(r.maybe_discontinuous);
    EXPECT_FALSE(r.maybe_undefined);
    IntervalValue away = interval_binary(Op::Div, iv(1, 1), iv(1, 2));
    EXPECT_EQ(away.value.lo, 0.5);
    EXPECT_EQ(away.value.hi, 1.0);
    EXPECT_FALSE(away.maybe_discontinuous);
}

TEST(IntervalMath, zero_over_interval_with_zero_may_be_undefined) {
    EXPECT_TRUE(interval_binary(Op::Div, iv(-1, 1), iv(0, 1)).maybe_undefined);
    EXPECT_TRUE(interval_binary(Op::Div, iv(1, 2), iv(0, 1)).maybe_discontinuous);
}

TEST(IntervalMath, tan_across_its_pole_is_discontinuous) {
    IntervalValue across = interval_unary(Op::Tan, iv(1.5, 1.6), 0);
    EXPECT_TRUE(across.maybe_discontinuous);
    EXPECT_EQ(across.value.lo, -kInf);
    IntervalValue before = interval_unary(Op::Tan, iv(0.0, 1.0), 0);
    EXPECT_FALSE(before.maybe_discontinuous);
    EXPECT_EQ(before.value.lo, 0.0);
    EXPECT_NEAR(before.value.hi, std::tan(1.0), 1e-14);
    EXPECT_TRUE(interval_unary(Op::Tan, iv(-4.8, -4.6), 0).maybe_discontinuous);  // -3pi/2
}

TEST(IntervalMath, ln_touching_zero_reaches_minus_infinity) {
    IntervalValue touching = interval_unary(Op::Ln, iv(0.0, 1.0), 0);
    EXPECT_EQ(touching.value.lo, -kInf);
    EXPECT_EQ(touching.value.hi, 0.0);
    EXPECT_TRUE(touching.maybe_discontinuous);
    EXPECT_FALSE(touching.maybe_undefined);
    IntervalValue crossing = interval_unary(Op::Ln, iv(-1.0, 1.0), 0);
    EXPECT_TRUE(crossing.maybe_undefined);
    IntervalValue negative = interval_unary(Op::Log10, iv(-2.0, -1.0), 0);
    EXPECT_TRUE(negative.value.is_empty());
    EXPECT_TRUE(negative.maybe_undefined);
    IntervalValue positive = interval_unary(Op::Log2, iv(1.0, 8.0), 0);
    EXPECT_FALSE(positive.maybe_undefined || positive.maybe_discontinuous);
    EXPECT_TRUE(positive.value.contains(0.0) && positive.value.contains(3.0));
}

TEST(IntervalMath, sqrt_of_partly_negative_interval_is_clipped) {
    IntervalValue r = interval_unary(Op::Sqrt, iv(-1.0, 4.0), 0);
    EXPECT_EQ(r.value.lo, 0.0);
    EXPECT_EQ(r.value.hi, 2.0);
    EXPECT_TRUE(r.maybe_undefined);
    EXPECT_FALSE(interval_unary(Op::Sqrt, iv(1.0, 4.0), 0).maybe_undefined);
    EXPECT_TRUE(interval_unary(Op::Sqrt, iv(-4.0, -1.0), 0).value.is_empty());
}

TEST(IntervalMath, sqrt_of_sum_of_squares_through_origin_is_defined) {
    IntervalValue sq = interval_unary(Op::Square, iv(-1.0, 2.0), 0);
    EXPECT_EQ(sq.value.lo, 0.0);
    IntervalValue r = interval_unary(Op::Sqrt, interval_binary(Op::Add, sq, sq), 0);
    EXPECT_FALSE(r.maybe_undefined);
    EXPECT_EQ(r.value.lo, 0.0);
    // A libm result that is exactly zero stays exact: sqrt(sin(x)) on [0, 1] is defined.
    IntervalValue s = interval_unary(Op::Sin, iv(0.0, 1.0), 0);
    EXPECT_FALSE(interval_unary(Op::Sqrt, s, 0).maybe_undefined);
}

TEST(IntervalMath, asin_and_acos_outside_unit_interval_may_be_undefined) {
    IntervalValue r = interval_unary(Op::Asin, iv(0.5, 2.0), 0);
    EXPECT_TRUE(r.maybe_undefined);
    EXPECT_NEAR(r.value.hi, kPi / 2, 1e-14);
    IntervalValue c = interval_unary(Op::Acos, iv(-1.0, 1.0), 0);
    EXPECT_FALSE(c.maybe_undefined);
    EXPECT_EQ(c.value.lo, 0.0);
    EXPECT_TRUE(interval_unary(Op::Acos, iv(1.5, 2.0), 0).value.is_empty());
}

TEST(IntervalMath, atan2_across_negative_x_axis_is_discontinuous) {
    IntervalValue cut = interval_binary(Op::Atan2, iv(-0.1, 0.1), iv(-2.0, -1.0));
    EXPECT_TRUE(cut.maybe_discontinuous);
    EXPECT_TRUE(cut.value.contains(kPi) && cut.value.contains(-kPi));
    IntervalValue right = interval_binary(Op::Atan2, iv(-0.1, 0.1), iv(1.0, 2.0));
    EXPECT_FALSE(right.maybe_discontinuous);
    EXPECT_LT(right.value.hi, 0.11);
    EXPECT_TRUE(interval_binary(Op::Atan2, iv(0.0, 1.0), iv(-1.0, -0.5)).maybe_discontinuous);
}

TEST(IntervalMath, sin_and_cos_reach_their_extrema_inside) {
    IntervalValue s = interval_unary(Op::Sin, iv(0.0, kPi), 0);
    EXPECT_EQ(s.value.hi, 1.0);
    EXPECT_LE(s.value.lo, 0.0);
    EXPECT_GT(s.value.lo, -1e-15);
    IntervalValue falling = interval_unary(Op::Sin, iv(1.6, 3.0), 0);
    EXPECT_NEAR(falling.value.lo, std::sin(3.0), 1e-14);
    EXPECT_NEAR(falling.value.hi, std::sin(1.6), 1e-14);
    EXPECT_EQ(interval_unary(Op::Cos, iv(-0.1, 0.1), 0).value.hi, 1.0);
    EXPECT_EQ(interval_unary(Op::Cos, iv(3.0, 3.3), 0).value.lo, -1.0);
    IntervalValue wide = interval_unary(Op::Cos, iv(0.0, 100.0), 0);
    EXPECT_EQ(wide.value.lo, -1.0);
    EXPECT_EQ(wide.value.hi, 1.0);
}

TEST(IntervalMath, steps_are_discontinuous_only_across_a_jump) {
    EXPECT_TRUE(interval_unary(Op::Floor, iv(0.5, 1.5), 0).maybe_discontinuous);
    EXPECT_FALSE(interval_unary(Op::Floor, iv(1.0, 1.5), 0).maybe_discontinuous);
    EXPECT_FALSE(interval_unary(Op::Ceil, iv(0.5, 1.0), 0).maybe_discontinuous);
    EXPECT_TRUE(interval_unary(Op::Round, iv(0.4, 0.6), 0).maybe_discontinuous);
    EXPECT_TRUE(interval_unary(Op::Sgn, iv(-1.0, 1.0), 0).maybe_discontinuous);
    EXPECT_FALSE(interval_unary(Op::Sgn, iv(0.5, 1.0), 0).maybe_discontinuous);
}

TEST(IntervalMath, whole_powers_keep_their_sign) {
    IntervalValue cube = interval_unary(Op::PowInt, iv(-2.0, 1.0), 3);
    EXPECT_EQ(cube.value.lo, -8.0);
    EXPECT_EQ(cube.value.hi, 1.0);
    IntervalValue fourth = interval_unary(Op::PowInt, iv(-2.0, 1.0), 4);
    EXPECT_EQ(fourth.value.lo, 0.0);
    EXPECT_EQ(fourth.value.hi, 16.0);
    EXPECT_TRUE(interval_unary(Op::PowInt, iv(-1.0, 1.0), -2).maybe_discontinuous);
    // x^0 is 1 even where x is undefined.
    IntervalValue zeroth = interval_unary(Op::PowInt, {Interval::empty(), false, true}, 0);
    EXPECT_EQ(zeroth.value.lo, 1.0);
    EXPECT_FALSE(zeroth.maybe_undefined);
}

TEST(IntervalMath, pow_of_negative_base_needs_whole_exponent) {
    IntervalValue half = interval_binary(Op::Pow, iv(-2.0, -1.0), iv(0.5, 0.5));
    EXPECT_TRUE(half.value.is_empty());
    EXPECT_TRUE(half.maybe_undefined);
    IntervalValue square = interval_binary(Op::Pow, iv(-2.0, -1.0), iv(2.0, 2.0));
    EXPECT_FALSE(square.maybe_undefined);
    EXPECT_TRUE(square.value.contains(1.0) && square.value.contains(4.0));
    EXPECT_LT(square.value.hi, 4.001);
    EXPECT_TRUE(interval_binary(Op::Pow, iv(-2.0, 2.0), iv(1.0, 3.0)).maybe_undefined);
    // pow(NaN, 0) = 1 and pow(1, NaN) = 1, as std::pow.
    EXPECT_TRUE(
        interval_binary(Op::Pow, {Interval::empty(), false, true}, iv(0, 0)).value.contains(1.0));
    EXPECT_TRUE(
        interval_binary(Op::Pow, iv(1, 1), {Interval::empty(), false, true}).value.contains(1.0));
}

TEST(IntervalMath, infinities_that_cancel_may_be_undefined) {
    EXPECT_TRUE(interval_binary(Op::Add, iv(1.0, kInf), iv(-kInf, 0.0)).maybe_undefined);
    EXPECT_FALSE(interval_binary(Op::Add, iv(1.0, kInf), iv(0.0, kInf)).maybe_undefined);
    IntervalValue zero_times = interval_binary(Op::Mul, iv(0.0, 0.0), iv(-kInf, kInf));
    EXPECT_TRUE(zero_times.maybe_undefined);
    EXPECT_TRUE(zero_times.value.contains(0.0));
}

TEST(IntervalMath, flags_propagate_from_operands) {
    IntervalValue jumpy{{0.0, 1.0}, true, false};
    IntervalValue partial{{0.0, 1.0}, false, true};
    IntervalValue sum = interval_binary(Op::Add, jumpy, partial);
    EXPECT_TRUE(sum.maybe_discontinuous && sum.maybe_undefined);
    IntervalValue e = interval_unary(Op::Exp, jumpy, 0);
    EXPECT_TRUE(e.maybe_discontinuous);
    EXPECT_FALSE(e.maybe_undefined);
}

TEST(IntervalMath, empty_operand_gives_empty_result) {
    IntervalValue nothing{Interval::empty(), false, true};
    for (Op op : {Op::Sin, Op::Exp, Op::Sqrt, Op::Neg}) {
        IntervalValue r = interval_unary(op, nothing, 0);
        EXPECT_TRUE(r.value.is_empty() && r.maybe_undefined) << op_name(op);
    }
    for (Op op : {Op::Add, Op::Mul, Op::Min, Op::Max, Op::Atan2}) {
        IntervalValue r = interval_binary(op, iv(0.0, 1.0), nothing);
        EXPECT_TRUE(r.value.is_empty() && r.maybe_undefined) << op_name(op);
    }
    EXPECT_TRUE(interval_constant(std::nan("")).value.is_empty());
}

TEST(IntervalMath, min_and_max_propagate_undefined) {
    IntervalValue r = interval_binary(Op::Min, iv(0.0, 1.0), {{5.0, 6.0}, false, true});
    EXPECT_EQ(r.value.lo, 0.0);
    EXPECT_EQ(r.value.hi, 1.0);
    EXPECT_TRUE(r.maybe_undefined);  // NaN propagates through min
}

TEST(IntervalMath, hull_ignores_empty) {
    Interval h = hull(Interval::empty(), {1.0, 2.0});
    EXPECT_EQ(h.lo, 1.0);
    EXPECT_EQ(h.hi, 2.0);
    EXPECT_TRUE(Interval::entire().contains(-kInf));
    EXPECT_TRUE(Interval::empty().is_empty());
}

}  // namespace
}  // namespace isomesh
