#include "refine/constraints.h"

#include <gtest/gtest.h>

namespace isomesh {
namespace {

MeshStats stats(std::size_t triangles, double total, double max) {
    return {triangles, total, max};
}

TEST(Constraint, default_never_refines_and_has_no_cap) {
    const Constraint c;
    EXPECT_FALSE(c.wants_refinement(stats(0, 1e9, 1e9)));
    EXPECT_FALSE(c.over_limit(stats(1'000'000, 0, 0)));
}

TEST(Constraint, leaves) {
    const Constraint budget = Constraint::triangle_budget(100);
    EXPECT_TRUE(budget.wants_refinement(stats(99, 0, 0)));
    EXPECT_FALSE(budget.wants_refinement(stats(100, 0, 0)));
    EXPECT_FALSE(budget.over_limit(stats(100, 0, 0)));
    EXPECT_TRUE(budget.over_limit(stats(101, 0, 0)));

    const Constraint local = Constraint::max_error(0.5);
    EXPECT_TRUE(local.wants_refinement(stats(10, 0, 0.6)));
    EXPECT_FALSE(local.wants_refinement(stats(10, 100, 0.5)));
    EXPECT_FALSE(local.over_limit(stats(1'000'000, 0, 0)));

    const Constraint global = Constraint::total_error(2.0);
    EXPECT_TRUE(global.wants_refinement(stats(10, 2.1, 0)));
    EXPECT_FALSE(global.wants_refinement(stats(10, 2.0, 5)));
}

// The thesis's delta(M) = (max error > alpha) and (|M| < N): the budget caps the refinement.
TEST(Constraint, and_refines_while_both_and_caps_if_any_part_caps) {
    const Constraint c = Constraint::max_error(0.1) && Constraint::triangle_budget(100);
    EXPECT_TRUE(c.wants_refinement(stats(50, 0, 0.2)));
    EXPECT_FALSE(c.wants_refinement(stats(50, 0, 0.05)));
    EXPECT_FALSE(c.wants_refinement(stats(100, 0, 0.2)));
    EXPECT_TRUE(c.over_limit(stats(101, 0, 0.0)));
    EXPECT_EQ(c.describe(), "(max_error > 0.1 and triangles < 100)");
}

TEST(Constraint, budget_and_error_bound_adds_the_bound_only_when_positive) {
    EXPECT_EQ(Constraint::budget_and_error_bound(100, 0.1).describe(),
              "(max_error > 0.1 and triangles < 100)");
    EXPECT_EQ(Constraint::budget_and_error_bound(100, 0.0).describe(), "triangles < 100");
}

// In an "or", a budget is a minimum count, not a cap.
TEST(Constraint, or_refines_while_either_and_caps_only_if_all_cap) {
    const Constraint c = Constraint::triangle_budget(100) || Constraint::total_error(1.0);
    EXPECT_TRUE(c.wants_refinement(stats(50, 0.5, 0)));
    EXPECT_TRUE(c.wants_refinement(stats(500, 1.5, 0)));
    EXPECT_FALSE(c.wants_refinement(stats(500, 0.5, 0)));
    EXPECT_FALSE(c.over_limit(stats(500, 0.5, 0)));
    const Constraint both = Constraint::triangle_budget(100) || Constraint::triangle_budget(200);
    EXPECT_FALSE(both.over_limit(stats(150, 0, 0)));
    EXPECT_TRUE(both.over_limit(stats(250, 0, 0)));
}

TEST(Constraint, not_and_custom) {
    const Constraint c = !Constraint::max_error(1.0);
    EXPECT_TRUE(c.wants_refinement(stats(1, 0, 0.5)));
    EXPECT_FALSE(c.wants_refinement(stats(1, 0, 2.0)));
    EXPECT_FALSE((!Constraint::triangle_budget(10)).over_limit(stats(100, 0, 0)));
    const Constraint even =
        Constraint::custom([](const MeshStats& s) { return s.triangles % 2 == 1; }, "odd");
    EXPECT_TRUE(even.wants_refinement(stats(3, 0, 0)));
    EXPECT_FALSE(even.wants_refinement(stats(4, 0, 0)));
    EXPECT_EQ((even || Constraint()).describe(), "(odd or never)");
    EXPECT_FALSE(Constraint::custom(nullptr).wants_refinement(stats(1, 1, 1)));
}

}  // namespace
}  // namespace isomesh
