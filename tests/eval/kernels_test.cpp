// The interval kernels against the reference evaluation they replace: bit-identical enclosures,
// flags, gradients and tape simplification, box by box and eight boxes at a time, on every test
// function and on the CAD models; and the kernels, not the reference, do the work on ordinary
// boxes.
#include "eval/interval_kernels.h"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include "eval/tape_field.h"
#include "support/shared_data.h"
#include "test_support.h"

namespace isomesh::testing {
namespace {

struct Case {
    std::string name;
    std::shared_ptr<const Tape> tape;
    std::vector<double> params;
    double scale;
    std::vector<glm::dvec3> special;
};

void PrintTo(const Case& c, std::ostream* os) {
    *os << c.name;
}

std::vector<Case> cases() {
    std::vector<Case> all;
    for (const TestFunction& f : test_functions())
        all.push_back({f.name, f.tape, f.params, f.scale, f.special});
    for (const char* model : {"bear", "colonnade"}) {
        all.push_back(
            {model,
             test::shared_data_present()
                 ? load_vm_tape(std::string(ISOMESH_SHARED_DIR "/testdata/vm/") + model + ".vm")
                 : nullptr,
             {},
             1.0,
             {}});
    }
    return all;
}

bool same(const Interval& a, const Interval& b) {
    return same_value(a.lo, b.lo) && same_value(a.hi, b.hi);
}

bool same(const IntervalValue& a, const IntervalValue& b) {
    return same(a.value, b.value) && a.maybe_discontinuous == b.maybe_discontinuous &&
           a.maybe_undefined == b.maybe_undefined;
}

bool same(const IntervalGradient& a, const IntervalGradient& b) {
    return same(a.value, b.value) && same(a.gradient[0], b.gradient[0]) &&
           same(a.gradient[1], b.gradient[1]) && same(a.gradient[2], b.gradient[2]);
}

std::string describe(const Interval& i) {
    std::ostringstream out;
    out.precision(17);
    out << "[" << i.lo << ", " << i.hi << "]";
    return out.str();
}

std::string describe(const IntervalValue& v) {
    return describe(v.value) + (v.maybe_discontinuous ? " discontinuous" : "") +
           (v.maybe_undefined ? " undefined" : "");
}

std::string describe(const IntervalGradient& g) {
    return describe(g.value) + " grad " + describe(g.gradient[0]) + " " + describe(g.gradient[1]) +
           " " + describe(g.gradient[2]);
}

std::string describe(const Box& b) {
    std::ostringstream out;
    out.precision(17);
    out << "box (" << b.lo.x << ", " << b.lo.y << ", " << b.lo.z << ") - (" << b.hi.x << ", "
        << b.hi.y << ", " << b.hi.z << ")";
    return out.str();
}

class Kernels : public ::testing::TestWithParam<Case> {
  protected:
    void SetUp() override {
        if (!GetParam().tape) GTEST_SKIP() << ISOMESH_NO_SHARED_DATA;
    }
    std::unique_ptr<Evaluator> make(bool reference, bool simplify = false) const {
        const Case& c = GetParam();
        return make_tape_field(c.tape, c.params, {.simplify = simplify, .reference = reference})
            ->make_evaluator();
    }
    std::vector<Box> boxes(std::uint64_t seed, int count) const {
        Rng rng(seed);
        std::vector<Box> all;
        for (int i = 0; i < count; ++i)
            all.push_back(random_box(rng, GetParam().scale, GetParam().special));
        return all;
    }
};

TEST_P(Kernels, match_reference_bitwise) {
    auto fast = make(false), reference = make(true);
    const std::vector<Box> all = boxes(21, 400);
    std::vector<IntervalValue> batch(kIntervalLanes);
    std::vector<IntervalGradient> gradient_batch(kIntervalLanes);
    for (std::size_t start = 0; start + kIntervalLanes <= all.size(); start += kIntervalLanes) {
        std::span<const Box> group(all.data() + start, kIntervalLanes);
        fast->intervals(group, batch);
        fast->interval_gradients(group, gradient_batch);
        for (std::size_t l = 0; l < kIntervalLanes; ++l) {
            const IntervalValue expected = reference->interval(group[l]);
            const IntervalGradient expected_gradient = reference->interval_gradient(group[l]);
            ASSERT_TRUE(same(fast->interval(group[l]), expected))
                << describe(group[l]) << ": " << describe(fast->interval(group[l])) << " vs "
                << describe(expected);
            ASSERT_TRUE(same(batch[l], expected)) << describe(group[l]) << " lane " << l;
            ASSERT_TRUE(same(fast->interval_gradient(group[l]), expected_gradient))
                << describe(group[l]) << ": " << describe(fast->interval_gradient(group[l]))
                << " vs " << describe(expected_gradient);
            ASSERT_TRUE(same(gradient_batch[l], expected_gradient))
                << describe(group[l]) << " lane " << l;
        }
    }
}

// Batches of every size run the one-box, the narrow (kIntervalFewLanes) and the wide kernels, a
// batch's last few boxes the narrow one: each lane equals the reference bit for bit.
TEST_P(Kernels, batches_of_any_size_match_reference_bitwise) {
    auto fast = make(false), reference = make(true);
    const std::vector<Box> all = boxes(24, 60);
    for (std::size_t size : {2u, 3u, 4u, 5u, 9u, 12u, 13u}) {
        std::span<const Box> group(all.data(), size);
        std::vector<IntervalValue> values(size);
        std::vector<IntervalGradient> gradients(size);
        fast->intervals(group, values);
        fast->interval_gradients(group, gradients);
        for (std::size_t l = 0; l < size; ++l) {
            ASSERT_TRUE(same(values[l], reference->interval(group[l])))
                << describe(group[l]) << " lane " << l << " of " << size;
            ASSERT_TRUE(same(gradients[l], reference->interval_gradient(group[l])))
                << describe(group[l]) << " lane " << l << " of " << size;
        }
    }
}

// Simplification from the kernels' choices (reused from the batch that just evaluated the box, or
// from a new evaluation) specialises the tape exactly as the reference's choices do.
TEST_P(Kernels, simplify_as_reference) {
    auto fast = make(false, true), reference = make(true, true);
    const std::vector<Box> all = boxes(22, 160);
    std::vector<IntervalGradient> batch(kIntervalLanes);
    for (std::size_t start = 0; start + kIntervalLanes <= all.size(); start += kIntervalLanes) {
        std::span<const Box> group(all.data() + start, kIntervalLanes);
        fast->interval_gradients(group, batch);
        for (std::size_t l = 0; l < kIntervalLanes; ++l) {
            fast->push(group[l]);
            reference->push(group[l]);
            ASSERT_EQ(active_tape_size(*fast), active_tape_size(*reference)) << describe(group[l]);
            const Box inner{group[l].lo, group[l].center()};
            ASSERT_TRUE(same(fast->interval_gradient(inner), reference->interval_gradient(inner)));
            fast->pop();
            reference->pop();
        }
    }
}

TEST_P(Kernels, point_gradients_match_reference_bitwise) {
    auto fast = make(false), reference = make(true);
    Rng rng(23);
    std::vector<glm::dvec3> points = GetParam().special;
    std::uniform_real_distribution<double> u(-GetParam().scale, GetParam().scale);
    for (int i = 0; i < 300; ++i) points.emplace_back(u(rng), u(rng), u(rng));
    std::vector<double> x, y, z;
    for (const auto& p : points) x.push_back(p.x), y.push_back(p.y), z.push_back(p.z);
    std::vector<ValueGradient> batch(points.size());
    fast->value_gradients({x, y, z}, batch);
    for (std::size_t i = 0; i < points.size(); ++i) {
        const ValueGradient expected = reference->value_gradient(points[i]);
        const ValueGradient single = fast->value_gradient(points[i]);
        ASSERT_TRUE(same_value(fast->value(points[i]), reference->value(points[i])));
        for (const ValueGradient& got : {single, batch[i]}) {
            ASSERT_TRUE(same_value(got.value, expected.value));
            for (int k = 0; k < 3; ++k) {
                ASSERT_TRUE(same_value(got.gradient[k], expected.gradient[k]))
                    << "d/d"
                    << "xyz"[k] << " " << got.gradient[k] << " vs " << expected.gradient[k];
            }
        }
    }
}

INSTANTIATE_TEST_SUITE_P(AllFunctions, Kernels, ::testing::ValuesIn(cases()),
                         [](const ::testing::TestParamInfo<Case>& info) {
                             return info.param.name;
                         });

// Tapes whose output is a leaf run the kernels' Const and variable steps only.
TEST(KernelLeaves, constant_and_variable_tapes_match_reference) {
    const std::vector<Box> boxes = {
        {{-1, 2, 3}, {1, 2.5, 4}}, {{0, 0, 0}, {0, 0, 0}}, {{-5, -4, -3}, {5, 4, 3}}};
    for (const Instruction& leaf :
         {Instruction{Op::Const, 0, 0, 2.5}, Instruction{Op::Const, 0, 0, std::nan("")},
          Instruction{Op::Const, 0, 0, -INFINITY}, Instruction{Op::VarY}}) {
        auto tape = std::make_shared<const Tape>(Tape{{leaf}, {}});
        auto fast = make_tape_field(tape, {})->make_evaluator();
        auto reference = make_tape_field(tape, {}, {.reference = true})->make_evaluator();
        std::vector<IntervalGradient> batch(boxes.size());
        fast->interval_gradients(boxes, batch);
        for (std::size_t i = 0; i < boxes.size(); ++i) {
            const IntervalGradient expected = reference->interval_gradient(boxes[i]);
            EXPECT_TRUE(same(batch[i], expected))
                << op_name(leaf.op) << " " << leaf.imm << ": " << describe(batch[i]) << " vs "
                << describe(expected);
            EXPECT_TRUE(same(fast->interval(boxes[i]), expected.value));
            EXPECT_TRUE(same(fast->interval_gradient(boxes[i]), expected));
        }
    }
}

// On an octree's boxes the kernels do the work: the reference code recomputes only the steps
// whose operands are not finite (here: the derivative of sqrt at the origin, infinite on the 8
// boxes touching it, and what follows from it there). The blobby cube's sqrt(x^2+y^2+z^2) is a
// hypot, whose derivative stays finite: 2z^2 keeps the sqrt.
TEST(IntervalKernelCounts, reference_recomputes_only_steps_with_infinities) {
    auto field =
        make_tape_field(compile_tape("sqrt(x^2+y^2+2z^2)+2cos(2x)+2cos(2y)+2cos(2z)=20"), {});
    auto e = field->make_evaluator();
    const double h = 28.0 / 8;
    for (int i = 0; i < 8; ++i)
        for (int j = 0; j < 8; ++j)
            for (int k = 0; k < 8; ++k) {
                glm::dvec3 lo(-14.0 + i * h, -14.0 + j * h, -14.0 + k * h);
                e->interval_gradient({lo, lo + h});
            }
    IntervalKernelCounts counts = interval_kernel_counts(*e);
    EXPECT_GT(counts.steps, 512u * 15);
    EXPECT_GE(counts.by_reference, 8u);
    EXPECT_LT(counts.by_reference, counts.steps / 100);
}

}  // namespace
}  // namespace isomesh::testing
