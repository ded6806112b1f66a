#include "polygonize/edge_roots.h"

#include <cmath>

#include <gtest/gtest.h>

#include "support/mesh_checks.h"

namespace isomesh {
namespace {

EdgeSegment x_edge(Evaluator& evaluator, double x0, double x1, double y = 0.3, double z = -0.2) {
    const glm::dvec3 a{x0, y, z}, b{x1, y, z};
    return {a, b, evaluator.value(a), evaluator.value(b), 0};
}

TEST(EdgeRoots, find_edge_root_converges_to_machine_precision) {
    const auto field = test::field_of("x^3+x-1+0*y*z");
    auto evaluator = field->make_evaluator();
    const EdgeRoot root = find_edge_root(*evaluator, x_edge(*evaluator, 0.0, 1.0));
    ASSERT_TRUE(root.found);
    EXPECT_NEAR(root.position.x, 0.6823278038280193, 1e-15);
    EXPECT_EQ(root.position.y, 0.3);  // stays on the edge exactly
    EXPECT_EQ(root.position.z, -0.2);
    EXPECT_LE(std::abs(root.value), 1e-15);
    EXPECT_NEAR(root.gradient.x, 3 * root.position.x * root.position.x + 1, 1e-12);
}

TEST(EdgeRoots, find_edge_root_returns_an_exact_end) {
    const auto field = test::field_of("x");
    auto evaluator = field->make_evaluator();
    const EdgeRoot root = find_edge_root(*evaluator, x_edge(*evaluator, -0.5, 0.0));
    ASSERT_TRUE(root.found);
    EXPECT_EQ(root.position.x, 0.0);
}

TEST(EdgeRoots, find_edge_root_handles_a_flat_root) {
    // A root of multiplicity 3 with a tiny slope: Newton alone crawls, bisection finishes.
    const auto field = test::field_of("(x-0.3)^3");
    auto evaluator = field->make_evaluator();
    const EdgeRoot root = find_edge_root(*evaluator, x_edge(*evaluator, -1.0, 1.0));
    ASSERT_TRUE(root.found);
    EXPECT_NEAR(root.position.x, 0.3, 1e-5);
}

TEST(EdgeRoots, find_edge_root_rejects_poles_and_jumps) {
    for (const char* expression :
         {"1/x", "tan(x+1.5707963267948966)", "floor(x)+0.5", "sgn(x)*2+x^2"}) {
        const auto field = test::field_of(expression);
        auto evaluator = field->make_evaluator();
        const EdgeRoot root = find_edge_root(*evaluator, x_edge(*evaluator, -0.37, 0.41));
        EXPECT_FALSE(root.found) << expression << " at x = " << root.position.x;
    }
}

TEST(EdgeRoots, find_edge_root_rejects_the_border_of_the_domain) {
    const auto field = test::field_of("sqrt(x)+1");  // NaN for x < 0, >= 1 elsewhere
    auto evaluator = field->make_evaluator();
    const EdgeSegment edge = x_edge(*evaluator, -0.5, 0.5);
    ASSERT_TRUE(std::isnan(edge.fa));
    EdgeSegment flipped = edge;  // NaN counts as outside: make the other end inside
    flipped.fb = -1.0;
    EXPECT_FALSE(find_edge_root(*evaluator, flipped).found);
}

TEST(EdgeRoots, count_edge_roots_proves_single_and_double_crossings) {
    const auto field = test::field_of("x^2-0.25+0*y*z");
    auto evaluator = field->make_evaluator();
    const EdgeRootCount one = count_edge_roots(*evaluator, x_edge(*evaluator, 0.1, 2.0), 1e-3);
    EXPECT_EQ(one.roots, 1);
    EXPECT_TRUE(one.proven);
    const EdgeRootCount two = count_edge_roots(*evaluator, x_edge(*evaluator, -1.0, 1.3), 1e-3);
    EXPECT_EQ(two.roots, 2);  // the ends agree in sign, but the edge is crossed twice
    const EdgeRootCount none = count_edge_roots(*evaluator, x_edge(*evaluator, -0.4, 0.4), 1e-3);
    EXPECT_EQ(none.roots, 0);
    EXPECT_FALSE(none.false_crossing);
}

TEST(EdgeRoots, count_edge_roots_tells_poles_from_roots) {
    const auto field = test::field_of("(x-0.5)/x");  // root at 0.5, pole at 0
    auto evaluator = field->make_evaluator();
    const EdgeRootCount pole = count_edge_roots(*evaluator, x_edge(*evaluator, -0.3, 0.2), 1e-4);
    EXPECT_EQ(pole.roots, 0);
    EXPECT_TRUE(pole.false_crossing);
    const EdgeRootCount root = count_edge_roots(*evaluator, x_edge(*evaluator, 0.2, 0.9), 1e-4);
    EXPECT_EQ(root.roots, 1);
    EXPECT_FALSE(root.false_crossing);
}

}  // namespace
}  // namespace isomesh
