#include "refine/surface_projection.h"

#include "refine/error_measures.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "fixtures.h"

namespace isomesh {
namespace {

TEST(ProjectToSurface, secant_along_the_direction_lands_on_a_sphere) {
    auto field = test::make_quadric_field({1, 1, 1}, 4.0);
    auto e = field->make_evaluator();
    const glm::dvec3 start(1.5, 0.3, -0.2);
    for (double slope : {0.0, 3.0}) {  // unknown, or roughly |grad f|
        const Projection p = project_to_surface(*e, {start, {1, 0.1, 0}, slope, 1.0, 0});
        EXPECT_EQ(p.method, ProjectionMethod::Secant);
        EXPECT_NEAR(glm::length(p.position), 2.0, 1e-9);
        EXPECT_NEAR(glm::length(glm::cross(p.position - start, glm::dvec3(1, 0.1, 0))), 0.0, 1e-12);
        EXPECT_NEAR(glm::dot(p.normal, glm::normalize(p.position)), 1.0, 1e-12);
        EXPECT_NEAR(p.gradient_norm, 4.0, 1e-8);
        EXPECT_LE(p.evaluations, 8);
    }
}

TEST(ProjectToSurface, newton_along_the_gradient_without_direction) {
    auto field = test::make_sphere_field({0, 0, 0}, 2.0);
    auto e = field->make_evaluator();
    const Projection p = project_to_surface(*e, {{1.5, 0.3, -0.2}, {0, 0, 0}, 0.0, 1.0, 0});
    EXPECT_EQ(p.method, ProjectionMethod::Newton);
    EXPECT_NEAR(glm::length(p.position), 2.0, 1e-9);
    EXPECT_NEAR(glm::dot(p.normal, glm::normalize(p.position)), 1.0, 1e-12);
}

TEST(ProjectToSurface, keeps_a_fixed_axis) {
    auto field = test::make_quadric_field({1, 1, 1}, 4.0);
    auto e = field->make_evaluator();
    const Projection p = project_to_surface(*e, {{1.0, 1.0, 0.5}, {1, 1, 0}, 0.0, 1.0, 0b100});
    ASSERT_TRUE(p.on_surface());
    EXPECT_EQ(p.position.z, 0.5);
    EXPECT_NEAR(glm::length(p.position), 2.0, 1e-9);
}

// A vertex on an edge of the meshing box (y and z fixed) moves along that edge only, even where
// its direction and the gradient point across it.
TEST(ProjectToSurface, keeps_two_fixed_axes) {
    auto field = test::make_quadric_field({1, 1, 1}, 4.0);
    auto e = field->make_evaluator();
    const Projection p = project_to_surface(*e, {{0.5, 1.0, 1.0}, {1, 1, 1}, 0.0, 2.0, 0b110});
    ASSERT_TRUE(p.on_surface());
    EXPECT_EQ(p.position.y, 1.0);
    EXPECT_EQ(p.position.z, 1.0);
    EXPECT_NEAR(p.position.x, std::sqrt(2.0), 1e-9);
}

// f = x^3 - 0.001 has a zero gradient at the start: Newton cannot move, bracketing finds x = 0.1.
TEST(ProjectToSurface, brackets_where_newton_fails) {
    auto field = test::make_analytic_field(
        {[](const glm::dvec3& p) { return p.x * p.x * p.x - 0.001; },
         [](const glm::dvec3& p) { return glm::dvec3(3 * p.x * p.x, 0, 0); }});
    auto e = field->make_evaluator();
    const Projection p = project_to_surface(*e, {{0, 0, 0}, {1, 0, 0}, 0.0, 1.0, 0});
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
    const Projection p = project_to_surface(*e, {start, {1, 0, 0}, 0.0, 1.0, 0});
    EXPECT_EQ(p.method, ProjectionMethod::Failed);
    EXPECT_EQ(p.position, start);
}

TEST(ProjectToSurface, fails_without_surface_within_reach) {
    auto field = test::make_sphere_field({0, 0, 0}, 10.0);
    auto e = field->make_evaluator();
    const Projection p = project_to_surface(*e, {{1, 0, 0}, {1, 0, 0}, 0.0, 1.0, 0});
    EXPECT_FALSE(p.on_surface());
    EXPECT_EQ(p.position, glm::dvec3(1, 0, 0));
    // Undefined everywhere: NaN values never count as roots.
    auto nan_field = test::make_analytic_field({[](const glm::dvec3&) { return std::nan(""); },
                                                [](const glm::dvec3&) { return glm::dvec3(0.0); }});
    auto n = nan_field->make_evaluator();
    EXPECT_FALSE(project_to_surface(*n, {{1, 0, 0}, {1, 0, 0}, 0.0, 1.0, 0}).on_surface());
    EXPECT_FALSE(project_to_surface(*e, {{1, 0, 0}, {1, 0, 0}, 0.0, 0.0, 0}).on_surface());
}

}  // namespace
}  // namespace isomesh

namespace isomesh {
namespace {

// Projection requests around the cosine sphere, some without direction,
// some without slope, some on a box face.
std::vector<ProjectionRequest> mixed_requests() {
    std::vector<ProjectionRequest> requests;
    for (int i = 0; i < 300; ++i) {
        const glm::dvec3 start(std::sin(i) * 2.0, std::cos(0.7 * i) * 2.0, std::sin(1.3 * i));
        const glm::dvec3 direction = i % 5 == 0 ? glm::dvec3(0.0) : start;
        requests.push_back({start, direction, i % 3 == 0 ? 0.0 : 3.0, 0.2 + (i % 7) * 0.1,
                            std::uint8_t(i % 11 == 0 ? 0b100 : 0)});
    }
    return requests;
}

bool same_projection(const Projection& a, const Projection& b) {
    return a.position == b.position && a.normal == b.normal && a.gradient_norm == b.gradient_norm &&
           a.method == b.method;
}

// The batched form gives the same projections bit for bit, failures and fallbacks included.
TEST(ProjectToSurface, batch_matches_one_at_a_time) {
    auto field = test::compile_field("x^2+y^2+z^2+2cos(2x)=5");
    auto e = field->make_evaluator();
    const std::vector<ProjectionRequest> requests = mixed_requests();
    std::vector<Projection> batch(requests.size());
    project_to_surface(*e, requests, batch);
    int methods[4] = {0, 0, 0, 0};
    for (std::size_t i = 0; i < requests.size(); ++i) {
        const Projection one = project_to_surface(*e, requests[i]);
        ASSERT_EQ(one.position, batch[i].position) << i;
        ASSERT_EQ(one.normal, batch[i].normal) << i;
        ASSERT_EQ(one.method, batch[i].method) << i;
        ++methods[int(one.method)];
    }
    EXPECT_GT(methods[int(ProjectionMethod::Secant)], 100);
    EXPECT_GT(methods[int(ProjectionMethod::Newton)], 10);
    EXPECT_GT(methods[int(ProjectionMethod::Failed)], 0);  // too far from the surface
}

// f(start) given by the caller (the refiner's error measure sampled it) is one evaluation fewer,
// and the same projection bit for bit.
TEST(ProjectToSurface, known_start_value_saves_an_evaluation_and_changes_nothing) {
    auto field = test::compile_field("x^2+y^2+z^2+2cos(2x)=5");
    auto e = field->make_evaluator();
    std::vector<ProjectionRequest> requests = mixed_requests();
    std::vector<Projection> unknown(requests.size()), known(requests.size());
    project_to_surface(*e, requests, unknown);
    for (ProjectionRequest& r : requests) r.start_value = e->value(r.start);
    project_to_surface(*e, requests, known);
    int saved = 0;
    for (std::size_t i = 0; i < requests.size(); ++i) {
        ASSERT_TRUE(same_projection(known[i], unknown[i])) << i;
        ASSERT_TRUE(same_projection(known[i], project_to_surface(*e, requests[i]))) << i;
        ASSERT_LE(known[i].evaluations, unknown[i].evaluations) << i;
        saved += unknown[i].evaluations - known[i].evaluations;
    }
    EXPECT_GT(saved, 150);  // every secant search with a direction
}

// Fed with gradients where it asks for them, the secant search visits the same points and ends
// on the same one, where it then hands over the gradient the check would have evaluated.
TEST(SecantSearch, gradients_where_it_asks_change_nothing_and_serve_the_check) {
    auto field = test::compile_field("x^2+y^2+z^2+2cos(2x)=5");
    auto e = field->make_evaluator();
    int served = 0, found = 0;
    for (const ProjectionRequest& request : mixed_requests()) {
        SecantSearch values(request, {});
        SecantSearch gradients(request, {});
        while (values.wants_value()) {
            ASSERT_TRUE(gradients.wants_value());
            const glm::dvec3 p = values.next_point();
            ASSERT_EQ(p, gradients.next_point());
            values.feed(e->value(p));
            if (gradients.wants_gradient())
                gradients.feed(e->value_gradient(p));
            else
                gradients.feed(e->value(p));
        }
        ASSERT_FALSE(gradients.wants_value());
        ASSERT_EQ(values.found(), gradients.found());
        EXPECT_EQ(values.found_gradient(), nullptr);
        if (!gradients.found()) continue;
        ++found;
        ASSERT_EQ(values.point(), gradients.point());
        if (const ValueGradient* vg = gradients.found_gradient()) {
            const ValueGradient fresh = e->value_gradient(gradients.point());
            EXPECT_EQ(vg->value, fresh.value);
            EXPECT_EQ(vg->gradient, fresh.gradient);
            ++served;
        }
    }
    EXPECT_GT(found, 100);
    EXPECT_GT(served, found / 2);  // the prediction is right more often than not
}

// Triangles near the cosine sphere, their projected midpoints the base midpoints moved by
// `offset`; every fourth without a gradient norm.
std::vector<TriangleGeometry> sample_triangles(int count, const glm::dvec3& offset) {
    std::vector<TriangleGeometry> triangles;
    for (int i = 0; i < count; ++i) {
        const glm::dvec3 a(std::sin(i), std::cos(i), 1.5), b = a + glm::dvec3(0.3, 0.1, 0),
                                                           c = a + glm::dvec3(0, 0.2, 0.1);
        triangles.push_back({a, b, c, 0.5 * (a + b) + offset, i % 4 ? 3.0 : 0.0});
    }
    return triangles;
}

TEST(ErrorMeasure, midpoint_values_are_f_at_the_base_midpoints) {
    auto field = test::compile_field("x^2+y^2+z^2+2cos(2x)=5");
    auto e = field->make_evaluator();
    const std::vector<TriangleGeometry> triangles = sample_triangles(50, glm::dvec3(0.0));
    for (const std::string& name : error_measure_names()) {
        auto measure = make_error_measure(name);
        std::vector<double> errors(triangles.size()), alone(triangles.size()),
            values(triangles.size());
        measure->errors_and_midpoint_values(*e, triangles, errors, values);
        measure->triangle_errors(*e, triangles, alone);
        for (std::size_t i = 0; i < triangles.size(); ++i) {
            ASSERT_EQ(errors[i], alone[i]) << name << " " << i;
            if (name == "epsilon4")  // evaluates nothing
                ASSERT_TRUE(std::isnan(values[i]));
            else
                ASSERT_EQ(values[i], e->value(0.5 * (triangles[i].a + triangles[i].b)));
        }
    }
}

TEST(ErrorMeasure, batch_matches_one_at_a_time) {
    auto field = test::compile_field("x^2+y^2+z^2+2cos(2x)=5");
    auto e = field->make_evaluator();
    const std::vector<TriangleGeometry> triangles =
        sample_triangles(100, glm::dvec3(0.0, 0.0, 0.01));
    for (const std::string& name : error_measure_names()) {
        auto measure = make_error_measure(name);
        ASSERT_TRUE(measure);
        std::vector<double> errors(triangles.size());
        measure->triangle_errors(*e, triangles, errors);
        for (std::size_t i = 0; i < triangles.size(); ++i) {
            ASSERT_EQ(errors[i], measure->triangle_error(*e, triangles[i])) << name << " " << i;
            ASSERT_GE(errors[i], 0.0);
        }
    }
    EXPECT_EQ(make_error_measure("no such measure"), nullptr);
    EXPECT_EQ(error_measure_names().front(), "distance");
}

}  // namespace
}  // namespace isomesh
