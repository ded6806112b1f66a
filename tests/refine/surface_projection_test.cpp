#include "refine/surface_projection.h"

#include <cmath>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "fixtures.h"

namespace isomesh {
namespace {

TEST(ProjectToSurface, newton_lands_on_a_sphere) {
    auto field = test::make_sphere_field({0, 0, 0}, 2.0);
    auto e = field->make_evaluator();
    const Projection p = project_to_surface(*e, {{1.5, 0.3, -0.2}, {1, 0, 0}, 1.0, -1});
    EXPECT_EQ(p.method, ProjectionMethod::Newton);
    EXPECT_NEAR(glm::length(p.position), 2.0, 1e-9);
    EXPECT_NEAR(glm::dot(p.normal, glm::normalize(p.position)), 1.0, 1e-12);
}

TEST(ProjectToSurface, keeps_a_fixed_axis) {
    auto field = test::make_quadric_field({1, 1, 1}, 4.0);
    auto e = field->make_evaluator();
    const Projection p = project_to_surface(*e, {{1.0, 1.0, 0.5}, {1, 1, 0}, 1.0, 2});
    ASSERT_TRUE(p.on_surface());
    EXPECT_EQ(p.position.z, 0.5);
    EXPECT_NEAR(glm::length(p.position), 2.0, 1e-9);
}

// f = x^3 - 0.001 has a zero gradient at the start: Newton cannot move, bracketing finds x = 0.1.
TEST(ProjectToSurface, brackets_where_newton_fails) {
    auto field = test::make_analytic_field(
        {[](const glm::dvec3& p) { return p.x * p.x * p.x - 0.001; },
         [](const glm::dvec3& p) { return glm::dvec3(3 * p.x * p.x, 0, 0); }});
    auto e = field->make_evaluator();
    const Projection p = project_to_surface(*e, {{0, 0, 0}, {1, 0, 0}, 1.0, -1});
    EXPECT_EQ(p.method, ProjectionMethod::Bracketing);
    EXPECT_NEAR(p.position.x, 0.1, 1e-9);
}

// 1/x changes sign at its pole: no root there, so the start stays.
TEST(ProjectToSurface, never_moves_to_a_pole) {
    auto field = test::make_analytic_field(
        {[](const glm::dvec3& p) { return 1.0 / p.x; },
         [](const glm::dvec3& p) { return glm::dvec3(-1.0 / (p.x * p.x), 0, 0); }});
    auto e = field->make_evaluator();
    const glm::dvec3 start(0.01, 0.2, 0.3);
    const Projection p = project_to_surface(*e, {start, {1, 0, 0}, 1.0, -1});
    EXPECT_EQ(p.method, ProjectionMethod::Failed);
    EXPECT_EQ(p.position, start);
}

TEST(ProjectToSurface, fails_without_surface_within_reach) {
    auto field = test::make_sphere_field({0, 0, 0}, 10.0);
    auto e = field->make_evaluator();
    const Projection p = project_to_surface(*e, {{1, 0, 0}, {1, 0, 0}, 1.0, -1});
    EXPECT_FALSE(p.on_surface());
    EXPECT_EQ(p.position, glm::dvec3(1, 0, 0));
    // Undefined everywhere: NaN values never count as roots.
    auto nan_field = test::make_analytic_field({[](const glm::dvec3&) { return std::nan(""); },
                                                [](const glm::dvec3&) { return glm::dvec3(0.0); }});
    auto n = nan_field->make_evaluator();
    EXPECT_FALSE(project_to_surface(*n, {{1, 0, 0}, {1, 0, 0}, 1.0, -1}).on_surface());
    EXPECT_FALSE(project_to_surface(*e, {{1, 0, 0}, {1, 0, 0}, 0.0, -1}).on_surface());
}

}  // namespace
}  // namespace isomesh
