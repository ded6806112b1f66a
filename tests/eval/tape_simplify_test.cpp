// Tape simplification on a box: shorter tapes where CSG branches are proven irrelevant, identical
// values inside the box.
#include "eval/tape_simplify.h"

#include <gtest/gtest.h>

#include "eval/tape_field.h"
#include "support/shared_data.h"
#include "test_support.h"

namespace isomesh {
namespace {

/// Two spheres far apart, joined: near one, the other is irrelevant.
constexpr const char* kTwoSpheres =
    "min(sqrt((x-2)^2+y^2+z^2)-1, sqrt((x+2)^2+y^2+z^2)-1 + 0.1 sin(5x)sin(5y)sin(5z))";

TEST(TapeSimplify, csg_union_drops_the_far_shape) {
    auto e = make_tape_field(testing::compile_tape(kTwoSpheres), {})->make_evaluator();
    const std::size_t full = active_tape_size(*e);
    Box near_right{{1.5, -0.5, -0.5}, {2.5, 0.5, 0.5}};
    e->push(near_right);
    EXPECT_LT(active_tape_size(*e), full / 2);
    EXPECT_DOUBLE_EQ(e->value({2.0, 0.0, 0.0}), -1.0);
    e->pop();
    EXPECT_EQ(active_tape_size(*e), full);
    Box between{{-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5}};  // equally far from both: nothing proven
    e->push(between);
    EXPECT_EQ(active_tape_size(*e), full);
    e->pop();
}

TEST(TapeSimplify, nested_pushes_only_shrink) {
    auto e = make_tape_field(testing::compile_tape("max(min(x, y), min(z, x + 3))"), {})
                 ->make_evaluator();
    const std::size_t full = active_tape_size(*e);
    e->push({{0, 0, 10}, {1, 1, 11}});  // max(min(x, y), x + 3) = x + 3 once min(z, x+3) = x+3
    std::size_t outer = active_tape_size(*e);
    EXPECT_LT(outer, full);
    e->push({{0, 0, 10}, {0.5, 0.5, 10.5}});
    EXPECT_LE(active_tape_size(*e), outer);
    EXPECT_EQ(e->value({0.25, 0.25, 10.25}), 3.25);
    e->pop();
    EXPECT_EQ(active_tape_size(*e), outer);
    e->pop();
    EXPECT_EQ(active_tape_size(*e), full);
}

TEST(TapeSimplify, keeps_branch_that_may_be_undefined) {
    // On x in [-1, 1], 5 < sqrt(x) + 10 always, but sqrt(x) is NaN for x < 0 and min propagates
    // NaN: dropping it would turn NaN into 5.
    auto e = make_tape_field(testing::compile_tape("min(5, sqrt(x) + 10)"), {})->make_evaluator();
    const std::size_t full = active_tape_size(*e);
    e->push({{-1, -1, -1}, {1, 1, 1}});
    EXPECT_EQ(active_tape_size(*e), full);
    EXPECT_TRUE(std::isnan(e->value({-0.5, 0, 0})));
    e->pop();
    e->push({{0, -1, -1}, {1, 1, 1}});
    EXPECT_EQ(active_tape_size(*e), 1u);  // the constant 5
    EXPECT_EQ(e->value({0.5, 0, 0}), 5.0);
    e->pop();
}

TEST(TapeSimplify, disabled_push_changes_nothing) {
    auto e = make_tape_field(testing::compile_tape(kTwoSpheres), {}, {.simplify = false})
                 ->make_evaluator();
    const std::size_t full = active_tape_size(*e);
    e->push({{1.5, -0.5, -0.5}, {2.5, 0.5, 0.5}});
    EXPECT_EQ(active_tape_size(*e), full);
    e->pop();
}

TEST(TapeSimplify, returns_nothing_without_proven_branch) {
    std::vector<Instruction> code = {{Op::VarX, 0, 0, 0}, {Op::VarY, 0, 0, 0}, {Op::Min, 0, 1, 0}};
    const std::vector<std::uint32_t> slots = {2};
    EXPECT_FALSE(simplify_on_box(code, slots, std::vector{Choice::Both}).has_value());
    auto simplified = simplify_on_box(code, slots, std::vector{Choice::A});
    ASSERT_TRUE(simplified.has_value());
    ASSERT_EQ(simplified->size(), 1u);
    EXPECT_EQ((*simplified)[0].op, Op::VarX);
}

TEST(TapeSimplify, proves_choices_from_enclosures) {
    const IntervalValue low{{0, 1}, false, false}, high{{2, 3}, false, false};
    const IntervalValue overlapping{{0.5, 2.5}, false, false};
    EXPECT_EQ(prove_choice(Op::Min, low, high), Choice::A);
    EXPECT_EQ(prove_choice(Op::Max, low, high), Choice::B);
    EXPECT_EQ(prove_choice(Op::Min, high, low), Choice::B);
    EXPECT_EQ(prove_choice(Op::Min, low, overlapping), Choice::Both);
    IntervalValue undefined_high = high;
    undefined_high.maybe_undefined = true;  // dropping it would turn its NaN into a number
    EXPECT_EQ(prove_choice(Op::Min, low, undefined_high), Choice::Both);
    EXPECT_EQ(prove_choice(Op::Max, low, undefined_high), Choice::B);
    EXPECT_EQ(prove_choice(Op::Min, {Interval::empty(), false, true}, high), Choice::Both);
}

// logsumexp returns an operand unchanged only beyond the cutoff: ahead by more than 40.
TEST(TapeSimplify, proves_logsumexp_choices_beyond_the_cutoff) {
    const IntervalValue low{{0, 1}, false, false}, near{{2, 30}, false, false};
    const IntervalValue far{{41.5, 50}, false, false};
    EXPECT_EQ(prove_choice(Op::LogSumExp, low, near), Choice::Both);
    EXPECT_EQ(prove_choice(Op::LogSumExp, far, low), Choice::A);
    EXPECT_EQ(prove_choice(Op::LogSumExp, low, far), Choice::B);
    EXPECT_EQ(prove_choice(Op::LogSumExp, far, near), Choice::Both);  // 41.5 - 30 < 40
    IntervalValue undefined_low = low;
    undefined_low.maybe_undefined = true;
    EXPECT_EQ(prove_choice(Op::LogSumExp, far, undefined_low), Choice::Both);
    EXPECT_EQ(log_sum_exp(far.value.lo, low.value.hi), far.value.lo);  // the cutoff in values
}

// prospero (7,866 instructions, hundreds of min/max): tiles of a 1024^2-style grid need a small
// part of the tape each, and evaluate to exactly the same values.
TEST(TapeSimplify, prospero_tiles_run_much_shorter_tapes) {
    ISOMESH_SKIP_WITHOUT_SHARED_DATA();
    auto field =
        make_tape_field(testing::load_vm_tape(ISOMESH_SHARED_DIR "/testdata/vm/prospero.vm"), {});
    auto tiled = field->make_evaluator(), plain = field->make_evaluator();
    const std::size_t full = active_tape_size(*tiled);
    EXPECT_GT(full, 6900u);  // after folding, sharing, and fusing its distances into hypot
    const int tiles = 16;    // 16 x 16 tiles over [-1, 1]^2
    std::size_t total = 0, largest = 0;
    for (int ty = 0; ty < tiles; ++ty) {
        for (int tx = 0; tx < tiles; ++tx) {
            Box tile{{-1.0 + 2.0 * tx / tiles, -1.0 + 2.0 * ty / tiles, 0.0},
                     {-1.0 + 2.0 * (tx + 1) / tiles, -1.0 + 2.0 * (ty + 1) / tiles, 0.0}};
            tiled->push(tile);
            total += active_tape_size(*tiled);
            largest = std::max(largest, active_tape_size(*tiled));
            std::vector<double> x, y, z, out(9);
            for (int i = 0; i < 9; ++i) {
                x.push_back(tile.lo.x + (i % 3) * 0.5 * (tile.hi.x - tile.lo.x));
                y.push_back(tile.lo.y + (i / 3) * 0.5 * (tile.hi.y - tile.lo.y));
                z.push_back(0.0);
            }
            tiled->values({x, y, z}, out);
            for (int i = 0; i < 9; ++i)
                ASSERT_TRUE(testing::same_value(out[i], plain->value({x[i], y[i], 0.0})));
            tiled->pop();
        }
    }
    double mean = static_cast<double>(total) / (tiles * tiles);
    EXPECT_LT(mean, full / 10.0) << "mean simplified tape " << mean << " of " << full;
    EXPECT_LT(largest, full);
}

}  // namespace
}  // namespace isomesh
