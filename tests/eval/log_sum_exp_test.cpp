// logsumexp, the fused smooth blend ln(exp(a) + exp(b)): its point values against the spelled-out
// form, and the tighter enclosures (value and gradient) that motivated fusing it, against the
// spelled-out form's over the same boxes; its tape simplification beyond the cutoff.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "eval/tape_field.h"
#include "eval/tape_ops.h"
#include "test_support.h"

namespace isomesh::testing {
namespace {

/// The smooth union of the planes x = 0 and y = 0 with sharpness k, as CAD tools write it:
/// -ln(exp(-k x) + exp(-k y)) / k. `fused`: through TapeBuilder (one logsumexp); otherwise the
/// spelled-out tape, written instruction by instruction (TapeBuilder would fuse it).
std::shared_ptr<const Tape> plane_blend(double k, bool fused) {
    if (fused) {
        return tape_of([k](auto x, auto y, auto) {
            using std::exp, std::log;
            return -log(exp(-k * x) + exp(-k * y)) / k;
        });
    }
    auto tape = std::make_shared<Tape>();
    tape->code = {
        {Op::VarX, 0, 0, 0.0}, {Op::VarY, 0, 0, 0.0}, {Op::Const, 0, 0, -k}, {Op::Mul, 2, 0, 0.0},
        {Op::Mul, 2, 1, 0.0},  {Op::Exp, 3, 0, 0.0},  {Op::Exp, 4, 0, 0.0},  {Op::Add, 5, 6, 0.0},
        {Op::Ln, 7, 0, 0.0},   {Op::Neg, 8, 0, 0.0},  {Op::Const, 0, 0, k},  {Op::Div, 9, 10, 0.0},
    };
    EXPECT_EQ(tape->validate(), "");
    return tape;
}

int count_ops(const Tape& tape, Op op) {
    int n = 0;
    for (const Instruction& i : tape.code) n += i.op == op;
    return n;
}

double width(const Interval& i) {
    return i.hi - i.lo;
}

TEST(LogSumExp, builder_fuses_the_spelled_out_blend) {
    auto fused = plane_blend(8.0, true);
    EXPECT_EQ(count_ops(*fused, Op::LogSumExp), 1);
    EXPECT_EQ(count_ops(*fused, Op::Exp), 0);
    EXPECT_EQ(count_ops(*fused, Op::Ln), 0);
}

// Point values agree with the spelled-out tape within a few rounding errors of the operands'
// scale (the blend's value is near 0 on the surface, so ulps of the result mean nothing there).
TEST(LogSumExp, point_values_match_the_spelled_out_form) {
    for (double k : {1.0, 8.0, 30.0}) {
        auto fused = make_tape_field(plane_blend(k, true), {})->make_evaluator();
        auto spelled = make_tape_field(plane_blend(k, false), {})->make_evaluator();
        Rng rng(static_cast<std::uint64_t>(k));
        std::uniform_real_distribution<double> u(-2.0, 2.0);
        for (int i = 0; i < 5000; ++i) {
            const glm::dvec3 p(u(rng), u(rng), u(rng));
            const double scale = std::max({1.0, std::fabs(p.x), std::fabs(p.y)});
            const double a = fused->value(p), b = spelled->value(p);
            ASSERT_LE(std::fabs(a - b), 8 * std::numeric_limits<double>::epsilon() * scale)
                << "k " << k << " at " << p.x << ", " << p.y << ": " << a << " vs " << b;
            const glm::dvec3 ga = fused->value_gradient(p).gradient;
            const glm::dvec3 gb = spelled->value_gradient(p).gradient;
            for (int axis = 0; axis < 2; ++axis)
                ASSERT_NEAR(ga[axis], gb[axis], 1e-14) << "k " << k << " d/d"
                                                       << "xy"[axis];
        }
    }
}

// Where an exponential overflows (k * |x| > 709) the spelled-out form is infinite; the fused one
// keeps the blend's value, min(x, y) there.
TEST(LogSumExp, stays_finite_where_the_exponentials_overflow) {
    auto e = make_tape_field(plane_blend(1000.0, true), {})->make_evaluator();
    EXPECT_EQ(e->value({-1.0, 0.5, 0.0}), -1.0);
    EXPECT_EQ(e->value({2.0, 1.5, 0.0}), 1.5);
    EXPECT_NEAR(e->value({0.25, 0.25, 0.0}), 0.25 - std::log(2.0) / 1000.0, 1e-15);
}

// The dependency problem the fusion removes: over a box the spelled-out gradient's enclosure is
// (k e^-kx dx + ...) / (e^-kx + e^-ky), numerator and denominator treated as unrelated, far wider
// than the true range; the blend's gradient is a convex combination of the planes' gradients,
// (w, 1 - w, 0) with w in [0, 1], and so is its enclosure.
TEST(LogSumExp, gradient_enclosure_stays_within_the_operands_gradients) {
    const double k = 8.0;
    auto fused = make_tape_field(plane_blend(k, true), {})->make_evaluator();
    auto spelled = make_tape_field(plane_blend(k, false), {})->make_evaluator();
    const double slack = 1e-12;
    Rng rng(5);
    std::uniform_real_distribution<double> u(-1.0, 1.0), size(0.01, 0.5);
    int tighter = 0;
    for (int i = 0; i < 500; ++i) {
        const glm::dvec3 lo(u(rng), u(rng), u(rng));
        const Box box{lo, lo + glm::dvec3(size(rng), size(rng), size(rng))};
        const IntervalGradient f = fused->interval_gradient(box);
        const IntervalGradient s = spelled->interval_gradient(box);
        for (int axis = 0; axis < 2; ++axis) {
            ASSERT_GE(f.gradient[axis].lo, -slack);
            ASSERT_LE(f.gradient[axis].hi, 1.0 + slack);
            ASSERT_LE(width(f.gradient[axis]), width(s.gradient[axis]) + slack);
            tighter += width(f.gradient[axis]) < 0.5 * width(s.gradient[axis]);
        }
        EXPECT_EQ(f.gradient[2].lo, 0.0);
        EXPECT_EQ(f.gradient[2].hi, 0.0);
        // The value: both are the exact range up to rounding (ln and exp are monotone).
        EXPECT_NEAR(f.value.value.lo, s.value.value.lo, 1e-12);
        EXPECT_NEAR(f.value.value.hi, s.value.value.hi, 1e-12);
    }
    EXPECT_GT(tighter, 200);  // of 1,000 components
}

// The weight's own enclosure makes the gradient tight near one operand: far on x's side of the
// crease (y - x > 1 with k = 8, weight of x above 0.9997) the x-derivative is within 1e-3 of 1.
TEST(LogSumExp, gradient_enclosure_narrows_away_from_the_crease) {
    auto e = make_tape_field(plane_blend(8.0, true), {})->make_evaluator();
    const IntervalGradient g = e->interval_gradient({{0.0, 1.1, 0.0}, {0.1, 1.3, 0.1}});
    EXPECT_GT(g.gradient[0].lo, 0.999);
    EXPECT_LT(g.gradient[1].hi, 1e-3);
}

// Beyond the cutoff (k |x - y| > 40) logsumexp is one operand exactly, and push() drops the other
// with everything only it uses; results inside the box are unchanged bit for bit.
TEST(LogSumExp, push_drops_the_operand_beyond_the_cutoff) {
    auto tape = tape_of([](auto x, auto y, auto z) {
        using std::exp, std::log, std::sin;
        return -log(exp(-30 * x) + exp(-30 * (y + sin(3 * z) * sin(2 * x)))) / 30;
    });
    auto field = make_tape_field(tape, {});
    auto pushed = field->make_evaluator(), plain = field->make_evaluator();
    const std::size_t full = active_tape_size(*pushed);
    // 30 x in [-60, -54], 30 (y + sin sin) in [0, 66]: the exponents differ by 54 or more.
    const Box far_from_crease{{-2.0, 1.0, -0.5}, {-1.8, 1.2, 0.5}};
    pushed->push(far_from_crease);
    EXPECT_LT(active_tape_size(*pushed), full / 2);
    Rng rng(3);
    for (const glm::dvec3& p : points_in(rng, far_from_crease, {}, 200)) {
        ASSERT_TRUE(same_value(pushed->value(p), plain->value(p)));
        EXPECT_NEAR(pushed->value(p), p.x, 1e-15);
        const ValueGradient a = pushed->value_gradient(p), b = plain->value_gradient(p);
        for (int k = 0; k < 3; ++k) ASSERT_TRUE(same_value(a.gradient[k], b.gradient[k]));
    }
    pushed->pop();
    const Box across{{-0.1, -0.1, -0.1}, {0.1, 0.1, 0.1}};
    pushed->push(across);
    EXPECT_EQ(active_tape_size(*pushed), full);
    pushed->pop();
}

}  // namespace
}  // namespace isomesh::testing
