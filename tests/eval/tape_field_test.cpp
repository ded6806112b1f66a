// make_tape_field: argument checks, parameters, degenerate tapes, threads, and the path from the
// expression compiler.
#include "eval/tape_field.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <thread>

#include "support/shared_data.h"
#include "test_support.h"

namespace isomesh {
namespace {

std::string error_of(std::shared_ptr<const Tape> tape, std::vector<double> params) {
    try {
        make_tape_field(std::move(tape), std::move(params));
    } catch (const std::invalid_argument& e) {
        return e.what();
    }
    return "";
}

TEST(MakeTapeField, refuses_null_tape) {
    EXPECT_NE(error_of(nullptr, {}).find("no tape"), std::string::npos);
}

TEST(MakeTapeField, refuses_invalid_tape) {
    auto tape = std::make_shared<Tape>();
    EXPECT_NE(error_of(tape, {}).find("empty tape"), std::string::npos);
    tape->code = {{Op::VarX, 0, 0, 0.0}, {Op::Add, 0, 5, 0.0}};
    EXPECT_NE(error_of(tape, {}).find("operand not before its use"), std::string::npos);
}

TEST(MakeTapeField, refuses_wrong_parameter_count) {
    auto tape = testing::compile_tape("a x + b");
    ASSERT_EQ(tape->params.size(), 2u);
    EXPECT_NE(error_of(tape, {1.0}).find("2 parameters but 1"), std::string::npos);
}

TEST(MakeTapeField, refuses_fractional_integer_power) {
    auto tape = std::make_shared<Tape>();
    tape->code = {{Op::VarX, 0, 0, 0.0}, {Op::PowInt, 0, 0, 2.5}};
    EXPECT_NE(error_of(tape, {}).find("integer exponent"), std::string::npos);
    tape->code[1].imm = 1e12;
    EXPECT_NE(error_of(tape, {}).find("integer exponent"), std::string::npos);
}

TEST(MakeTapeField, parameters_rebind_without_recompiling) {
    auto tape = testing::compile_tape("a x^2 + b = z");
    ASSERT_EQ(tape->params, (std::vector<std::string>{"a", "b"}));
    auto first = make_tape_field(tape, {1.5, 2.0})->make_evaluator();
    auto second = make_tape_field(tape, {-1.0, 0.5})->make_evaluator();
    glm::dvec3 p(2.0, 0.0, 1.0);
    EXPECT_EQ(first->value(p), 1.5 * 4 + 2.0 - 1.0);
    EXPECT_EQ(second->value(p), -1.0 * 4 + 0.5 - 1.0);
    EXPECT_EQ(first->value_gradient(p).gradient.x, 1.5 * 2 * 2);
    IntervalValue iv = second->interval({{1.0, 0.0, 0.0}, {2.0, 0.0, 0.0}});
    EXPECT_EQ(iv.value.lo, -4.0 + 0.5);
    EXPECT_EQ(iv.value.hi, -1.0 + 0.5);
}

TEST(MakeTapeField, domain_is_infinite) {
    Box domain = make_tape_field(testing::compile_tape("x"), {})->domain();
    EXPECT_TRUE(std::isinf(domain.lo.x) && domain.lo.x < 0);
    EXPECT_TRUE(std::isinf(domain.hi.z) && domain.hi.z > 0);
}

TEST(TapeEvaluator, constant_and_variable_tapes_fill_batches) {
    auto constant = std::make_shared<const Tape>(Tape{{{Op::Const, 0, 0, 2.5}}, {}});
    auto variable = std::make_shared<const Tape>(Tape{{{Op::VarY, 0, 0, 0.0}}, {}});
    std::vector<double> x = {1, 2, 3}, y = {4, 5, 6}, z = {7, 8, 9}, out(3);
    make_tape_field(constant, {})->make_evaluator()->values({x, y, z}, out);
    EXPECT_EQ(out, (std::vector<double>{2.5, 2.5, 2.5}));
    make_tape_field(variable, {})->make_evaluator()->values({x, y, z}, out);
    EXPECT_EQ(out, y);
    auto e = make_tape_field(variable, {})->make_evaluator();
    EXPECT_EQ(e->value_gradient({0, 4, 0}).gradient, glm::dvec3(0, 1, 0));
}

// Batch loops are written for speed (min and max differently from op_math.h); every operation
// must still give the point evaluator's bits on zeros of both signs, infinities and NaN.
TEST(TapeEvaluator, batch_matches_point_on_special_values) {
    const std::vector<double> special = {std::nan(""), -INFINITY, -2.5, -1.0, -0.5, -0.0,
                                         0.0,          0.5,       1.0,  2.0,  3.0,  INFINITY};
    std::vector<double> xs, ys, zs, out;
    for (double x : special)
        for (double y : special) xs.push_back(x), ys.push_back(y), zs.push_back(0.0);
    out.resize(xs.size());
    for (int op_index = static_cast<int>(Op::Neg); op_index < kOpCount; ++op_index) {
        Op op = static_cast<Op>(op_index);
        Tape tape;
        tape.code = {
            {Op::VarX, 0, 0, 0.0}, {Op::VarY, 0, 0, 0.0}, {op, 0, 1, op == Op::PowInt ? 3.0 : 0.0}};
        auto e = make_tape_field(std::make_shared<const Tape>(tape), {})->make_evaluator();
        e->values({xs, ys, zs}, out);
        for (std::size_t i = 0; i < xs.size(); ++i) {
            ASSERT_TRUE(testing::same_value(out[i], e->value({xs[i], ys[i], 0.0})))
                << op_name(op) << "(" << xs[i] << ", " << ys[i] << "): batch " << out[i];
        }
    }
}

TEST(TapeEvaluator, one_over_x_is_flagged_discontinuous_at_zero) {
    auto e = make_tape_field(testing::compile_tape("1/x = 0"), {})->make_evaluator();
    IntervalValue across = e->interval({{-1, -1, -1}, {1, 1, 1}});
    EXPECT_TRUE(across.maybe_discontinuous);
    IntervalValue away = e->interval({{0.5, -1, -1}, {1, 1, 1}});
    EXPECT_FALSE(away.maybe_discontinuous);
    EXPECT_TRUE(away.value.excludes_zero());
}

TEST(TapeEvaluator, interval_gradient_proves_monotone_edges) {
    auto e = make_tape_field(testing::compile_tape("x^2+y^2+z^2=1"), {})->make_evaluator();
    IntervalGradient g = e->interval_gradient({{0.9, -0.1, -0.1}, {1.1, 0.1, 0.1}});
    EXPECT_GE(g.gradient[0].lo, 1.8);
    EXPECT_LE(g.gradient[0].hi, 2.2);
    EXPECT_GE(g.gradient[1].lo, -0.2);
    EXPECT_LE(g.gradient[1].hi, 0.2);
}

TEST(TapeEvaluator, evaluators_of_one_field_run_concurrently) {
    ISOMESH_SKIP_WITHOUT_SHARED_DATA();
    auto field =
        make_tape_field(testing::load_vm_tape(ISOMESH_SHARED_DIR "/testdata/vm/bear.vm"), {});
    std::vector<double> xs(2000), ys(2000), zs(2000, 0.1);
    for (std::size_t i = 0; i < xs.size(); ++i) xs[i] = -1.0 + 0.001 * i, ys[i] = 0.3 - 0.0002 * i;
    std::vector<double> expected(xs.size()), a(xs.size()), b(xs.size());
    field->make_evaluator()->values({xs, ys, zs}, expected);
    auto run = [&](std::vector<double>& out) {
        auto e = field->make_evaluator();
        e->push({{-1, -0.1, 0.1}, {1, 0.3, 0.1}});
        e->values({xs, ys, zs}, out);
        e->pop();
    };
    std::thread first(run, std::ref(a)), second(run, std::ref(b));
    first.join();
    second.join();
    for (std::size_t i = 0; i < xs.size(); ++i) {
        ASSERT_TRUE(testing::same_value(a[i], expected[i]));
        ASSERT_TRUE(testing::same_value(b[i], expected[i]));
    }
}

TEST(TapeEvaluator, pop_without_push_keeps_the_tape) {
    auto e = make_tape_field(testing::compile_tape("min(x, y)"), {})->make_evaluator();
    // A contract violation: the assert stops it where asserts are compiled in (ISOMESH_ASSERTS),
    // and without them it is harmless.
    EXPECT_DEBUG_DEATH(e->pop(), "pop\\(\\) without push\\(\\)");
    EXPECT_EQ(active_tape_size(*e), 3u);
    EXPECT_EQ(e->value({1, 2, 0}), 1.0);
}

}  // namespace
}  // namespace isomesh
