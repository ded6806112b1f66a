// The evaluator conformance suite: every Field backend (tape fields with and without
// simplification, grid fields) against the contract of eval/evaluator.h, on the functions of
// test_support.cpp. Checks that cannot apply to a backend (a std:: reference for a sampled grid)
// are skipped for it.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include <glm/geometric.hpp>

#include "eval/batch_kernels.h"
#include "eval/grid_field.h"
#include "eval/tape_field.h"
#include "test_support.h"

namespace isomesh::testing {
namespace {

struct Backend {
    std::string name;
    std::shared_ptr<const Field> field;
    TestFunction function;  // its tape is null and reference empty for grids
};

/// Test output names the case rather than dumping its bytes.
void PrintTo(const Backend& c, std::ostream* os) {
    *os << c.name;
}

/// A grid sampling g on an uneven lattice over a box, so cells are not cubes.
template <class G>
IsoGrid sampled_grid(int nx, int ny, int nz, const Box& box, const G& g) {
    IsoGrid grid{nx, ny, nz, box, {}};
    for (int k = 0; k < nz; ++k)
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i) {
                glm::dvec3 t(i / (nx - 1.0), j / (ny - 1.0), k / (nz - 1.0));
                grid.samples.push_back(static_cast<float>(g(box.lo + t * box.size())));
            }
    return grid;
}

std::vector<Backend> backends() {
    std::vector<Backend> all;
    for (const TestFunction& f : test_functions()) {
        all.push_back(
            {f.name + "_simplified", make_tape_field(f.tape, f.params, {.simplify = true}), f});
        all.push_back(
            {f.name + "_plain", make_tape_field(f.tape, f.params, {.simplify = false}), f});
    }
    Box box{{-1.5, -1.2, -1.0}, {1.5, 1.3, 1.6}};
    IsoGrid smooth = sampled_grid(9, 7, 11, box, [](const glm::dvec3& p) {
        return p.x * p.x + p.y * p.y + p.z * p.z - 1.0 + 0.3 * std::sin(4 * p.x);
    });
    std::vector<glm::dvec3> faces = {{0.0, 0.05, 0.04}, {-1.5, -1.2, -1.0}, {1.5, 1.3, 1.6}};
    all.push_back(
        {"grid_smooth", make_grid_field(smooth), {"grid_smooth", nullptr, {}, {}, 1.8, faces}});
    Rng rng(7);
    IsoGrid noisy = sampled_grid(5, 4, 3, {{0, 0, 0}, {1, 1, 1}}, [&rng](const glm::dvec3&) {
        return std::uniform_real_distribution<double>(-1.0, 1.0)(rng);
    });
    all.push_back({"grid_noisy",
                   make_grid_field(noisy),
                   {"grid_noisy", nullptr, {}, {}, 1.2, {{0.25, 1.0 / 3, 0.5}}}});
    return all;
}

class EvaluatorConformance : public ::testing::TestWithParam<Backend> {
  protected:
    const TestFunction& function() const { return GetParam().function; }
    std::unique_ptr<Evaluator> evaluator() const { return GetParam().field->make_evaluator(); }

    /// Random points over the sampling cube, after the special points unless told otherwise.
    std::vector<glm::dvec3> random_points(Rng& rng, int count, bool with_special = true) const {
        double s = function().scale;
        std::vector<glm::dvec3> points;
        if (with_special) points = function().special;
        std::uniform_real_distribution<double> u(-s, s);
        for (int i = 0; i < count; ++i) points.emplace_back(u(rng), u(rng), u(rng));
        return points;
    }

    /// Calls check(box, points) on `count` random boxes with points inside each (see
    /// test_support.h), stopping at the first box that fails.
    template <class Check>
    void for_random_boxes(std::uint64_t seed, int count, int points_per_box, const Check& check) {
        Rng rng(seed);
        for (int n = 0; n < count && !HasFailure(); ++n) {
            Box box = random_box(rng, function().scale, function().special);
            check(box, points_in(rng, box, function().special, points_per_box));
        }
    }
};

std::string describe(const glm::dvec3& p) {
    std::ostringstream out;
    out.precision(17);
    out << "(" << p.x << ", " << p.y << ", " << p.z << ")";
    return out.str();
}

std::string describe(const Box& box, const Interval& i) {
    std::ostringstream out;
    out.precision(17);
    out << "box " << describe(box.lo) << " - " << describe(box.hi) << " interval [" << i.lo << ", "
        << i.hi << "]";
    return out.str();
}

TEST_P(EvaluatorConformance, values_match_point_bitwise) {
    auto e = evaluator();
    Rng rng(1);
    for (std::size_t n : {0, 1, 255, 256, 257, 1000}) {
        std::vector<glm::dvec3> points = random_points(rng, static_cast<int>(n));
        points.resize(n);
        std::vector<double> x, y, z, out(n, 0.0);
        for (const auto& p : points) x.push_back(p.x), y.push_back(p.y), z.push_back(p.z);
        e->values({x, y, z}, out);
        for (std::size_t i = 0; i < n; ++i) {
            ASSERT_TRUE(same_value(out[i], e->value(points[i])))
                << "at " << describe(points[i]) << " batch " << out[i] << " point "
                << e->value(points[i]);
        }
    }
}

// The tape evaluator runs batches of exactly kSmallBatch points with loops of that count (the
// refiner's error measure); the sizes beside it take the general loops.
TEST_P(EvaluatorConformance, values_of_small_batches_match_point_bitwise) {
    auto e = evaluator();
    Rng rng(2);
    for (std::size_t n : {kSmallBatch - 1, kSmallBatch, kSmallBatch + 1}) {
        // The special points first (in the first batches), then random ones.
        const std::vector<glm::dvec3> points = random_points(rng, static_cast<int>(40 * n));
        for (std::size_t start = 0; start + n <= points.size(); start += n) {
            std::vector<double> x, y, z, out(n, 0.0);
            for (std::size_t i = start; i < start + n; ++i)
                x.push_back(points[i].x), y.push_back(points[i].y), z.push_back(points[i].z);
            e->values({x, y, z}, out);
            for (std::size_t i = 0; i < n; ++i) {
                ASSERT_TRUE(same_value(out[i], e->value(points[start + i])))
                    << "at " << describe(points[start + i]) << " batch of " << n << ": " << out[i]
                    << " point " << e->value(points[start + i]);
            }
        }
    }
}

TEST_P(EvaluatorConformance, value_gradient_value_matches_point_bitwise) {
    auto e = evaluator();
    Rng rng(2);
    for (const auto& p : random_points(rng, 500)) {
        ASSERT_TRUE(same_value(e->value_gradient(p).value, e->value(p))) << "at " << describe(p);
    }
}

TEST_P(EvaluatorConformance, value_matches_std_reference) {
    if (!function().reference) GTEST_SKIP() << "no closed form for a sampled grid";
    auto e = evaluator();
    Rng rng(3);
    for (const auto& p : random_points(rng, 500)) {
        double expected = function().reference(p), v = e->value(p);
        if (std::isnan(expected)) {
            EXPECT_TRUE(std::isnan(v)) << "at " << describe(p);
        } else if (std::isinf(expected)) {
            EXPECT_EQ(v, expected) << "at " << describe(p);
        } else {
            EXPECT_NEAR(v, expected, 1e-12 * std::max(1.0, std::fabs(expected)))
                << "at " << describe(p);
        }
    }
}

TEST_P(EvaluatorConformance, interval_contains_every_point_value) {
    auto e = evaluator();
    for_random_boxes(4, 400, 30, [&](const Box& box, const std::vector<glm::dvec3>& points) {
        IntervalValue iv = e->interval(box);
        for (const auto& p : points) {
            double v = e->value(p);
            ASSERT_TRUE(std::isnan(v) ? iv.maybe_undefined : iv.value.contains(v))
                << describe(box, iv.value) << " undefined " << iv.maybe_undefined << " misses f"
                << describe(p) << " = " << v;
        }
    });
}

TEST_P(EvaluatorConformance, interval_gradient_contains_point_gradients) {
    auto e = evaluator();
    for_random_boxes(5, 300, 20, [&](const Box& box, const std::vector<glm::dvec3>& points) {
        IntervalGradient ig = e->interval_gradient(box);
        IntervalValue iv = e->interval(box);
        ASSERT_TRUE(same_value(ig.value.value.lo, iv.value.lo) &&
                    same_value(ig.value.value.hi, iv.value.hi));
        ASSERT_EQ(ig.value.maybe_undefined, iv.maybe_undefined);
        for (const auto& p : points) {
            glm::dvec3 g = e->value_gradient(p).gradient;
            for (int k = 0; k < 3; ++k) {
                ASSERT_TRUE(!std::isfinite(g[k]) || ig.gradient[k].contains(g[k]))
                    << describe(box, ig.gradient[k]) << " misses d/d"
                    << "xyz"[k] << " f" << describe(p) << " = " << g[k];
            }
        }
    });
}

// Where a box is flagged neither discontinuous nor undefined, f is continuous and differentiable
// almost everywhere on it, so the interval gradient bounds how far apart two values can be (mean
// value theorem). A jump the flags missed (floor at an integer, a pole) breaks the bound.
TEST_P(EvaluatorConformance, unflagged_box_obeys_gradient_bound) {
    auto e = evaluator();
    int checked = 0;
    for_random_boxes(9, 300, 10, [&](const Box& box, const std::vector<glm::dvec3>& points) {
        IntervalGradient ig = e->interval_gradient(box);
        if (ig.value.maybe_discontinuous || ig.value.maybe_undefined) return;
        glm::dvec3 lipschitz;
        for (int k = 0; k < 3; ++k)
            lipschitz[k] = std::max(std::fabs(ig.gradient[k].lo), std::fabs(ig.gradient[k].hi));
        if (!std::isfinite(lipschitz.x + lipschitz.y + lipschitz.z)) return;
        ++checked;
        double f0 = e->value(points[0]);
        for (const auto& p : points) {
            double f = e->value(p);
            double bound = glm::dot(lipschitz, glm::abs(p - points[0]));
            double rounding = 1e-12 * (1.0 + std::fabs(f) + std::fabs(f0));
            ASSERT_LE(std::fabs(f - f0), bound + rounding)
                << "f" << describe(points[0]) << " = " << f0 << ", f" << describe(p) << " = " << f;
        }
    });
    EXPECT_GT(checked, 20);
}

TEST_P(EvaluatorConformance, gradient_matches_central_differences) {
    auto e = evaluator();
    Rng rng(6);
    int checked = 0, defined = 0;
    // Not at the special points: there a kink may be symmetric, which fools the check below.
    for (const auto& p : random_points(rng, 300, false)) {
        glm::dvec3 g = e->value_gradient(p).gradient;
        if (std::isnan(e->value(p))) continue;
        for (int k = 0; k < 3; ++k) {
            ++defined;
            auto difference = [&](double h) {
                glm::dvec3 step(0.0);
                step[k] = h;
                return (e->value(p + step) - e->value(p - step)) / (2 * h);
            };
            double h = 1e-4 * std::max(1.0, std::fabs(p[k]));
            double coarse = difference(h), fine = difference(h / 2);
            double tolerance = 1e-4 * std::max(1.0, std::fabs(fine));
            double rounding = 1e-15 * std::fabs(e->value(p)) / h;
            // Where the two estimates disagree, a pole, jump or kink is too close to tell; where f
            // is huge, rounding swamps the difference.
            if (!std::isfinite(coarse) || !std::isfinite(fine) ||
                std::fabs(coarse - fine) > tolerance || rounding > tolerance)
                continue;
            ++checked;
            EXPECT_NEAR(g[k], fine, tolerance) << "d/d"
                                               << "xyz"[k] << " at " << describe(p);
        }
    }
    // Every function is smooth almost everywhere it is defined.
    EXPECT_GT(checked, defined * 9 / 10);
}

TEST_P(EvaluatorConformance, push_keeps_results_inside_box) {
    auto plain = evaluator(), pushed = evaluator();
    const std::size_t full_size = active_tape_size(*pushed);
    int n = 0;
    for_random_boxes(8, 150, 20, [&](const Box& box, std::vector<glm::dvec3> points) {
        pushed->push(box);
        bool nested = ++n % 2 == 0;  // then evaluate in a second push, on the lower octant
        Box inner = nested ? Box{box.lo, box.center()} : box;
        if (nested) {
            pushed->push(inner);
            for (auto& p : points) p = glm::clamp(p, inner.lo, inner.hi);
        }
        std::vector<double> x, y, z, batch(points.size());
        for (const auto& p : points) {
            x.push_back(p.x), y.push_back(p.y), z.push_back(p.z);
            ASSERT_TRUE(same_value(pushed->value(p), plain->value(p))) << describe(p);
            ValueGradient a = pushed->value_gradient(p), b = plain->value_gradient(p);
            ASSERT_TRUE(same_value(a.value, b.value));
            for (int k = 0; k < 3; ++k) ASSERT_TRUE(same_value(a.gradient[k], b.gradient[k]));
        }
        pushed->values({x, y, z}, batch);
        IntervalValue iv = pushed->interval(inner);
        for (std::size_t i = 0; i < points.size(); ++i) {
            double v = plain->value(points[i]);
            ASSERT_TRUE(same_value(batch[i], v)) << describe(points[i]);
            ASSERT_TRUE(std::isnan(v) ? iv.maybe_undefined : iv.value.contains(v))
                << describe(points[i]);
        }
        if (nested) pushed->pop();
        pushed->pop();
        ASSERT_EQ(active_tape_size(*pushed), full_size);
    });
}

bool same_interval(const Interval& a, const Interval& b) {
    return same_value(a.lo, b.lo) && same_value(a.hi, b.hi);
}

bool same_interval_value(const IntervalValue& a, const IntervalValue& b) {
    return same_interval(a.value, b.value) && a.maybe_discontinuous == b.maybe_discontinuous &&
           a.maybe_undefined == b.maybe_undefined;
}

// The batched forms give each point or box the single call's bits, for batches of every size
// around the evaluators' lane counts (an octree cell's 8 children, blocks of 256 points).
TEST_P(EvaluatorConformance, batched_forms_match_single_calls_bitwise) {
    auto batched = evaluator(), single = evaluator();
    Rng rng(10);
    for (std::size_t n : {1, 2, 7, 8, 9, 17}) {
        std::vector<Box> boxes;
        for (std::size_t i = 0; i < n; ++i)
            boxes.push_back(random_box(rng, function().scale, function().special));
        std::vector<IntervalValue> values(n);
        std::vector<IntervalGradient> gradients(n);
        batched->intervals(boxes, values);
        batched->interval_gradients(boxes, gradients);
        for (std::size_t i = 0; i < n; ++i) {
            ASSERT_TRUE(same_interval_value(values[i], single->interval(boxes[i])))
                << "batch of " << n << ", " << describe(boxes[i], values[i].value);
            const IntervalGradient g = single->interval_gradient(boxes[i]);
            ASSERT_TRUE(same_interval_value(gradients[i].value, g.value))
                << "batch of " << n << ", " << describe(boxes[i], gradients[i].value.value);
            for (int k = 0; k < 3; ++k)
                ASSERT_TRUE(same_interval(gradients[i].gradient[k], g.gradient[k]))
                    << "batch of " << n << ", " << describe(boxes[i], gradients[i].gradient[k]);
        }
    }
    for (std::size_t n : {1, 3, 8, 255, 257}) {
        std::vector<glm::dvec3> points = random_points(rng, static_cast<int>(n));
        points.resize(n);
        std::vector<double> x, y, z;
        for (const auto& p : points) x.push_back(p.x), y.push_back(p.y), z.push_back(p.z);
        std::vector<ValueGradient> out(n);
        batched->value_gradients({x, y, z}, out);
        for (std::size_t i = 0; i < n; ++i) {
            const ValueGradient vg = single->value_gradient(points[i]);
            ASSERT_TRUE(same_value(out[i].value, vg.value)) << describe(points[i]);
            for (int k = 0; k < 3; ++k)
                ASSERT_TRUE(same_value(out[i].gradient[k], vg.gradient[k]))
                    << "d/d"
                    << "xyz"[k] << " at " << describe(points[i]);
        }
    }
}

INSTANTIATE_TEST_SUITE_P(AllBackends, EvaluatorConformance, ::testing::ValuesIn(backends()),
                         [](const ::testing::TestParamInfo<Backend>& info) {
                             return info.param.name;
                         });

}  // namespace
}  // namespace isomesh::testing
