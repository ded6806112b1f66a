// hypot, the fused Euclidean norm sqrt(a^2 + b^2 (+ c^2)): its point values against the
// spelled-out form, its exact value enclosure, and the gradient enclosure that motivated fusing it
// (the exact range of each coordinate of the unit vector (a, b, c) / r, against the spelled-out
// form's [a] / [r]), over the same boxes; the kink at r = 0.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include <glm/geometric.hpp>

#include "eval/tape_field.h"
#include "test_support.h"

namespace isomesh::testing {
namespace {

const glm::dvec3 kCentre{0.3, -0.2, 0.1};

/// The distance from kCentre, as CAD models write it: sqrt((x-cx)^2 + (y-cy)^2 + (z-cz)^2).
/// `fused`: through TapeBuilder (hypot); otherwise the spelled-out tape, written instruction by
/// instruction (TapeBuilder would fuse it).
std::shared_ptr<const Tape> distance(bool fused) {
    if (fused) {
        return tape_of([](auto x, auto y, auto z) {
            using std::sqrt;
            auto dx = x - kCentre.x, dy = y - kCentre.y, dz = z - kCentre.z;
            return sqrt(dx * dx + dy * dy + dz * dz);
        });
    }
    auto tape = std::make_shared<Tape>();
    tape->code = {
        {Op::VarX, 0, 0, 0.0},        {Op::VarY, 0, 0, 0.0},        {Op::VarZ, 0, 0, 0.0},
        {Op::Const, 0, 0, kCentre.x}, {Op::Const, 0, 0, kCentre.y}, {Op::Const, 0, 0, kCentre.z},
        {Op::Sub, 0, 3, 0.0},         {Op::Sub, 1, 4, 0.0},         {Op::Sub, 2, 5, 0.0},
        {Op::Square, 6, 0, 0.0},      {Op::Square, 7, 0, 0.0},      {Op::Square, 8, 0, 0.0},
        {Op::Add, 9, 10, 0.0},        {Op::Add, 12, 11, 0.0},       {Op::Sqrt, 13, 0, 0.0},
    };
    EXPECT_EQ(tape->validate(), "");
    return tape;
}

int count_ops(const Tape& tape, Op op) {
    return static_cast<int>(std::count_if(tape.code.begin(), tape.code.end(),
                                          [op](const auto& i) { return i.op == op; }));
}

double width(const Interval& i) {
    return i.hi - i.lo;
}

TEST(Hypot, builder_fuses_square_roots_of_sums_of_squares) {
    EXPECT_EQ(count_ops(*distance(true), Op::Hypot), 2);
    EXPECT_EQ(count_ops(*distance(true), Op::Sqrt), 0);
    EXPECT_EQ(count_ops(*distance(true), Op::Square), 0);
    auto two = tape_of([](auto x, auto y, auto) { return sqrt(x * x + pow(y, 2)); });
    EXPECT_EQ(count_ops(*two, Op::Hypot), 1);
    // Not a sum of squares only: left as written.
    auto offset = tape_of([](auto x, auto y, auto) { return sqrt(x * x + y * y + 1.0); });
    EXPECT_EQ(count_ops(*offset, Op::Hypot), 0);
    auto single = tape_of([](auto x, auto, auto) { return sqrt(x * x); });
    EXPECT_EQ(count_ops(*single, Op::Hypot), 0);
}

// Point values agree with the spelled-out tape within a few ulps, gradients within rounding.
TEST(Hypot, point_values_match_the_spelled_out_form) {
    auto fused = make_tape_field(distance(true), {})->make_evaluator();
    auto spelled = make_tape_field(distance(false), {})->make_evaluator();
    Rng rng(11);
    std::uniform_real_distribution<double> u(-2.0, 2.0);
    for (int i = 0; i < 5000; ++i) {
        const glm::dvec3 p(u(rng), u(rng), u(rng));
        const double a = fused->value(p), b = spelled->value(p);
        ASSERT_LE(std::fabs(a - b), 4 * std::numeric_limits<double>::epsilon() * b)
            << p.x << ", " << p.y << ", " << p.z;
        const glm::dvec3 ga = fused->value_gradient(p).gradient;
        const glm::dvec3 gb = spelled->value_gradient(p).gradient;
        for (int k = 0; k < 3; ++k) ASSERT_NEAR(ga[k], gb[k], 1e-14);
    }
}

// The value enclosure is the norm of the box of (x - cx, y - cy, z - cz): from the distance of
// kCentre to the box to that of its farthest corner (no widening: + * sqrt round monotonically).
TEST(Hypot, interval_is_the_exact_range) {
    auto e = make_tape_field(distance(true), {})->make_evaluator();
    Rng rng(12);
    std::uniform_real_distribution<double> u(-1.0, 1.0), size(0.0, 0.6);
    for (int i = 0; i < 500; ++i) {
        const glm::dvec3 lo(u(rng), u(rng), u(rng));
        const Box box{lo, lo + glm::dvec3(size(rng), size(rng), size(rng))};
        const glm::dvec3 nearest = glm::clamp(kCentre, box.lo, box.hi);
        const glm::dvec3 farthest =
            glm::max(glm::abs(box.lo - kCentre), glm::abs(box.hi - kCentre));
        const Interval r = e->interval(box).value;
        EXPECT_NEAR(r.lo, glm::length(nearest - kCentre), 1e-15);
        EXPECT_NEAR(r.hi, glm::length(farthest), 1e-15);
    }
}

// The dependency problem the fusion removes: the spelled-out gradient (x - cx) / r is enclosed as
// [x - cx] / [r], numerator and denominator unrelated; the fused one multiplies exact ranges of
// unit vectors' coordinates (two nested hypots: (x - cx) / r = (h / r) ((x - cx) / h) with
// h = hypot(x - cx, y - cy)), within [-1, 1]. Counted over random boxes: the fused enclosure is
// the tighter one in most of them, though the nested product can be wider than the spelled-out
// quotient where the box nears the axis h = 0 (a three-operand norm would not be).
TEST(Hypot, gradient_enclosure_is_mostly_tighter_than_the_spelled_out_form) {
    auto fused = make_tape_field(distance(true), {})->make_evaluator();
    auto spelled = make_tape_field(distance(false), {})->make_evaluator();
    Rng rng(13);
    std::uniform_real_distribution<double> u(-1.0, 1.0), size(0.01, 0.3);
    int tighter = 0, compared = 0;
    for (int i = 0; i < 500; ++i) {
        const glm::dvec3 lo(u(rng), u(rng), u(rng));
        const Box box{lo, lo + glm::dvec3(size(rng), size(rng), size(rng))};
        const IntervalGradient f = fused->interval_gradient(box);
        const IntervalGradient s = spelled->interval_gradient(box);
        for (int k = 0; k < 3; ++k) {
            // Within [-1, 1] (widened by 1.25 per hypot where a box nears the kink).
            ASSERT_GE(f.gradient[k].lo, -1.25 * 1.25);
            ASSERT_LE(f.gradient[k].hi, 1.25 * 1.25);
            if (!std::isfinite(width(s.gradient[k]))) continue;  // the box nears kCentre
            ++compared;
            tighter += width(f.gradient[k]) < width(s.gradient[k]);
        }
    }
    EXPECT_GT(tighter, compared * 2 / 3);
}

// Far from the centre the unit vector barely turns over a small box: its enclosure is that narrow.
TEST(Hypot, gradient_enclosure_is_narrow_far_from_the_centre) {
    auto e = make_tape_field(distance(true), {})->make_evaluator();
    const Box box{{1.3, 0.8, 1.1}, {1.35, 0.85, 1.15}};  // about 1.6 from kCentre, 0.05 across
    const IntervalGradient g = e->interval_gradient(box);
    for (int k = 0; k < 3; ++k)
        EXPECT_LT(width(g.gradient[k]), 0.1) << "d/d"
                                             << "xyz"[k];
}

// At r = 0, the norm's kink, the point gradient is 0 (as the spelled-out form's, and abs's at 0)
// and the enclosure over a box holding the kink stays finite, cut to each operand's sign.
TEST(Hypot, kink_at_the_origin_has_a_bounded_gradient) {
    auto e = make_tape_field(distance(true), {})->make_evaluator();
    const ValueGradient at_centre = e->value_gradient(kCentre);
    EXPECT_EQ(at_centre.value, 0.0);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(at_centre.gradient[k], 0.0);
    const IntervalGradient around = e->interval_gradient({kCentre - 0.1, kCentre + 0.1});
    EXPECT_FALSE(around.value.maybe_undefined);
    for (int k = 0; k < 3; ++k) {
        EXPECT_GE(around.gradient[k].lo, -1.25 * 1.25);
        EXPECT_LE(around.gradient[k].hi, 1.25 * 1.25);
    }
    // The distance to the quadrant x, y >= 0 (as rounded boxes write it): on a box where y <= 0
    // the y-coordinate is 0 and its gradient [0, 0]; the x-derivative is in [0, 1.25].
    auto quadrant = tape_of([](auto x, auto y, auto) {
        auto zero = constant_like(x, 0.0);
        auto qx = maximum(x, zero), qy = maximum(y, zero);
        return sqrt(qx * qx + qy * qy);
    });
    auto q = make_tape_field(quadrant, {})->make_evaluator();
    const IntervalGradient g = q->interval_gradient({{-0.1, -0.3, 0.0}, {0.2, -0.1, 0.1}});
    EXPECT_GE(g.gradient[0].lo, 0.0);
    EXPECT_LE(g.gradient[0].hi, 1.25);
    EXPECT_EQ(g.gradient[1].lo, 0.0);
    EXPECT_EQ(g.gradient[1].hi, 0.0);
}

}  // namespace
}  // namespace isomesh::testing
