#include "polygonize/uniform_grid_mesher.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <stdexcept>
#include <vector>

#include <glm/geometric.hpp>

#include "mesh/topology.h"

namespace isomesh {
namespace {

/// Samples f on an n^3 grid over box.
std::vector<double> sample(const std::function<double(glm::dvec3)>& f, const Box& box, int n) {
    std::vector<double> values;
    const glm::dvec3 step = box.size() / static_cast<double>(n - 1);
    for (int k = 0; k < n; ++k) {
        for (int j = 0; j < n; ++j) {
            for (int i = 0; i < n; ++i) values.push_back(f(box.lo + glm::dvec3(i, j, k) * step));
        }
    }
    return values;
}

const Box kBox{{-2.0, -2.0, -2.0}, {2.0, 2.0, 2.0}};

double sphere(glm::dvec3 p) {
    return glm::length(p) - 1.5;
}
double torus(glm::dvec3 p) {
    const double ring = std::hypot(p.x, p.y) - 1.2;
    return std::hypot(ring, p.z) - 0.5;
}

TEST(UniformGridMesher, sphere_is_closed_outward_and_on_the_surface) {
    const int n = 30;
    const std::vector<double> values = sample(sphere, kBox, n);
    const Mesh mesh = mesh_sampled_grid({n, n, n, kBox, values});
    const TopologyReport report = analyze_topology(mesh);
    EXPECT_TRUE(report.watertight());
    EXPECT_TRUE(report.manifold());
    EXPECT_EQ(report.inconsistently_oriented_edges, 0u);
    EXPECT_EQ(report.components, 1u);
    EXPECT_EQ(report.euler_characteristic, 2);
    const double exact = 4.0 / 3.0 * M_PI * 1.5 * 1.5 * 1.5;
    EXPECT_NEAR(signed_volume(mesh), exact, 0.02 * exact);
    ASSERT_EQ(mesh.normals.size(), mesh.positions.size());
    for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
        EXPECT_NEAR(glm::length(mesh.positions[v]), 1.5, 0.01);
        EXPECT_GT(glm::dot(mesh.normals[v], glm::normalize(mesh.positions[v])), 0.99);
    }
}

TEST(UniformGridMesher, torus_has_genus_one) {
    const int n = 41;
    const std::vector<double> values = sample(torus, kBox, n);
    const TopologyReport report = analyze_topology(mesh_sampled_grid({n, n, n, kBox, values}));
    EXPECT_TRUE(report.watertight());
    EXPECT_TRUE(report.manifold());
    EXPECT_EQ(report.components, 1u);
    EXPECT_EQ(report.euler_characteristic, 0);
}

TEST(UniformGridMesher, surface_leaving_the_box_is_open_there_only) {
    const Box box{{0.0, -2.0, -2.0}, {2.0, 2.0, 2.0}};  // half a sphere
    const int n = 21;
    const std::vector<double> values = sample(sphere, box, n);
    const Mesh mesh = mesh_sampled_grid({n, n, n, box, values});
    const TopologyReport report = analyze_topology(mesh);
    EXPECT_GT(report.boundary_edges, 0u);
    EXPECT_EQ(report.nonmanifold_edges, 0u);
    EXPECT_EQ(report.euler_characteristic, 1);  // a disk
}

TEST(UniformGridMesher, cells_with_undefined_samples_are_skipped) {
    const int n = 11;
    std::vector<double> values = sample(sphere, kBox, n);
    values[5 + n * (5 + n * 5)] = std::nan("");  // the centre, inside: no surface near it
    const TopologyReport report = analyze_topology(mesh_sampled_grid({n, n, n, kBox, values}));
    EXPECT_TRUE(report.watertight());
    EXPECT_EQ(report.euler_characteristic, 2);
}

TEST(UniformGridMesher, bad_grids_are_rejected) {
    const std::vector<double> values(8, 1.0);
    EXPECT_THROW(mesh_sampled_grid({1, 2, 4, kBox, values}), std::invalid_argument);
    EXPECT_THROW(mesh_sampled_grid({2, 2, 3, kBox, values}), std::invalid_argument);
    const Box flat{{0.0, 0.0, 0.0}, {1.0, 0.0, 1.0}};
    EXPECT_THROW(mesh_sampled_grid({2, 2, 2, flat, values}), std::invalid_argument);
    const Box infinite{{0.0, 0.0, 0.0}, {INFINITY, 1.0, 1.0}};
    EXPECT_THROW(mesh_sampled_grid({2, 2, 2, infinite, values}), std::invalid_argument);
}

/// An evaluator of a C++ function, for the sampling entry point (value and values only).
class FunctionEvaluator : public Evaluator {
  public:
    explicit FunctionEvaluator(std::function<double(glm::dvec3)> f) : f_(std::move(f)) {}
    double value(const glm::dvec3& p) override { return f_(p); }
    void values(const PointBatch& points, std::span<double> out) override {
        ++batches;
        for (std::size_t i = 0; i < points.size(); ++i)
            out[i] = f_({points.x[i], points.y[i], points.z[i]});
    }
    IntervalValue interval(const Box&) override { return {Interval::entire(), true, true}; }
    ValueGradient value_gradient(const glm::dvec3& p) override { return {f_(p), glm::dvec3(0.0)}; }
    IntervalGradient interval_gradient(const Box& box) override {
        return {interval(box), {Interval::entire(), Interval::entire(), Interval::entire()}};
    }
    int batches = 0;

  private:
    std::function<double(glm::dvec3)> f_;
};

TEST(UniformGridMesher, evaluator_entry_samples_in_batches_and_matches_the_grid) {
    FunctionEvaluator evaluator(torus);
    const Mesh mesh = mesh_uniform_grid(evaluator, kBox, 40);
    EXPECT_EQ(evaluator.batches, 41);  // one per z-layer
    const std::vector<double> values = sample(torus, kBox, 41);
    const Mesh reference = mesh_sampled_grid({41, 41, 41, kBox, values});
    EXPECT_EQ(mesh.triangles, reference.triangles);
    ASSERT_EQ(mesh.positions.size(), reference.positions.size());
    for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
        EXPECT_LT(glm::distance(mesh.positions[v], reference.positions[v]), 1e-12);
    }
    EXPECT_THROW(mesh_uniform_grid(evaluator, kBox, 0), std::invalid_argument);
}

}  // namespace
}  // namespace isomesh
