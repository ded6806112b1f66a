#include "refine/refiner.h"

#include <atomic>
#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "fixtures.h"
#include "mesh/topology.h"

namespace isomesh {
namespace {

using test::canonical;
using test::check_conforming;

std::shared_ptr<const Field> spheroid() {
    return test::make_quadric_field({10, 1, 1}, 20);
}

RefineSettings budget_settings(std::size_t triangles) {
    RefineSettings s;
    s.constraint = Constraint::triangle_budget(triangles);
    return s;
}

// Steps with `ops` operations until converged, checking the mesh after every step.
std::vector<MeshDelta> run_checked(Refiner& refiner, std::size_t ops,
                                   test::Boundary boundary = test::Boundary::None) {
    std::vector<MeshDelta> deltas;
    for (int guard = 0; guard < 100000; ++guard) {
        StepResult r = refiner.step({ops});
        deltas.push_back(std::move(r.delta));
        const std::string problem = check_conforming(refiner.mesh().mesh, boundary);
        EXPECT_EQ(problem, "") << "after step " << guard;
        if (!problem.empty() || r.converged) break;
    }
    return deltas;
}

TEST(Refiner, splits_keep_a_closed_mesh_conforming_after_every_step) {
    auto field = spheroid();
    const Mesh first = test::cube_sphere_mesh(*field, 3);
    ASSERT_EQ(check_conforming(first), "");
    Refiner refiner(field, first, budget_settings(3000));
    run_checked(refiner, 37);
    const RefinedMesh m = refiner.mesh();
    const TopologyReport report = analyze_topology(m.mesh);
    EXPECT_EQ(report.components, 1u);
    EXPECT_EQ(report.euler_characteristic, 2);
    EXPECT_GE(m.mesh.triangles.size(), 2999u);
    EXPECT_GT(refiner.counters().splits, 1000u);
    // Every new vertex is on the surface.
    auto e = field->make_evaluator();
    for (const glm::dvec3& p : m.mesh.positions) {
        const ValueGradient vg = e->value_gradient(p);
        ASSERT_LT(std::abs(vg.value) / glm::length(vg.gradient), 1e-8);
    }
}

TEST(Refiner, boundary_edges_split_alone_and_stay_on_the_box_face) {
    auto field = test::make_quadric_field({1, 2, 3}, 4);
    const Mesh first = test::half_cube_sphere_mesh(*field, 4);
    ASSERT_EQ(check_conforming(first, test::Boundary::OnBoxFaces), "");
    Refiner refiner(field, first, budget_settings(1501));
    run_checked(refiner, 50, test::Boundary::OnBoxFaces);
    const RefinedMesh m = refiner.mesh();
    EXPECT_GE(m.mesh.triangles.size(), 1500u);  // odd counts are reachable with boundary splits
    EXPECT_LE(m.mesh.triangles.size(), 1501u);
    const TopologyReport report = analyze_topology(m.mesh);
    EXPECT_EQ(report.euler_characteristic, 1);  // a disc
    std::size_t on_plane = 0;
    for (std::size_t t = 0; t < m.mesh.triangles.size(); ++t)
        for (int e = 0; e < 3; ++e)
            if (m.mesh.neighbours[t][e] == kNoNeighbour) {
                EXPECT_EQ(m.mesh.positions[m.mesh.triangles[t][e]].z, 0.0);
                ++on_plane;
            }
    EXPECT_GT(on_plane, 4u * 4u);  // the boundary was refined too
}

TEST(Refiner, deltas_replay_to_the_same_mesh) {
    auto field = spheroid();
    Refiner refiner(field, test::cube_sphere_mesh(*field, 3), budget_settings(2000));
    const MeshDelta start = refiner.snapshot();
    std::vector<MeshDelta> deltas = run_checked(refiner, 100);
    refiner.set_constraint(Constraint::triangle_budget(700));  // merges
    for (auto& d : run_checked(refiner, 64)) deltas.push_back(std::move(d));
    refiner.set_field(test::make_quadric_field({9, 1.2, 1}, 21));  // moves
    refiner.set_constraint(Constraint::triangle_budget(1200));
    for (auto& d : run_checked(refiner, 64)) deltas.push_back(std::move(d));
    std::string error;
    const Mesh replayed = test::replay_mesh(start, deltas, &error);
    EXPECT_EQ(error, "");
    const Mesh own = canonical(refiner.mesh());
    EXPECT_TRUE(test::same_mesh(replayed, own));
    EXPECT_EQ(replayed.normals, own.normals);
    // The snapshot alone gives the same mesh too.
    EXPECT_TRUE(test::same_mesh(test::replay_mesh(refiner.snapshot(), {}, nullptr), own));
}

TEST(Refiner, result_does_not_depend_on_step_sizes) {
    auto field = spheroid();
    const Mesh first = test::cube_sphere_mesh(*field, 3);
    for (QueueKind queue : {QueueKind::Bucket, QueueKind::Heap}) {
        std::vector<RefinedMesh> results;
        for (std::size_t ops : {1u, 7u, 1000u}) {
            RefineSettings s = budget_settings(1500);
            s.queue = queue;
            Refiner refiner(field, first, s);
            while (!refiner.step({ops}).converged) {
            }
            refiner.set_constraint(Constraint::triangle_budget(900));
            while (!refiner.step({ops}).converged) {
            }
            results.push_back(refiner.mesh());
        }
        for (std::size_t i = 1; i < results.size(); ++i) {
            EXPECT_TRUE(test::same_mesh(results[0].mesh, results[i].mesh));
            EXPECT_EQ(results[0].triangle_ids, results[i].triangle_ids);
            EXPECT_EQ(results[0].vertex_ids, results[i].vertex_ids);
        }
    }
}

TEST(Refiner, triangle_budget_met_within_one_without_overshooting) {
    auto field = spheroid();
    const Mesh first = test::cube_sphere_mesh(*field, 2);
    for (std::size_t budget : {100u, 501u, 1000u, 2345u}) {
        Refiner refiner(field, first, budget_settings(budget));
        for (;;) {
            const StepResult r = refiner.step({13});
            ASSERT_LE(refiner.stats().triangles, budget);
            if (r.converged) break;
        }
        EXPECT_GE(refiner.stats().triangles + 1, budget) << budget;
    }
}

TEST(Refiner, merging_after_splitting_returns_the_first_mesh) {
    auto field = spheroid();
    const Mesh first = test::cube_sphere_mesh(*field, 3);
    Refiner refiner(field, first, budget_settings(2500));
    const RefinedMesh before = refiner.mesh();
    refiner.run_to_convergence();
    ASSERT_GT(refiner.stats().triangles, 2000u);
    refiner.set_constraint(Constraint::triangle_budget(0));  // coarsen as far as possible
    refiner.run_to_convergence();
    const RefinedMesh after = refiner.mesh();
    EXPECT_TRUE(test::same_mesh(canonical(before), canonical(after)));
    EXPECT_EQ(before.triangle_ids, after.triangle_ids);
    EXPECT_EQ(refiner.counters().merges, refiner.counters().splits);
}

TEST(Refiner, lowering_a_budget_coarsens_and_raising_it_refines_again) {
    auto field = spheroid();
    Refiner refiner(field, test::cube_sphere_mesh(*field, 3), budget_settings(4000));
    refiner.run_to_convergence();
    const std::size_t splits = refiner.counters().splits;
    refiner.set_constraint(Constraint::triangle_budget(1501));
    const StepResult r = refiner.run_to_convergence();
    EXPECT_GT(r.merges, 0u);
    EXPECT_LE(refiner.stats().triangles, 1501u);
    EXPECT_GE(refiner.stats().triangles, 1500u);
    EXPECT_EQ(check_conforming(refiner.mesh().mesh), "");
    refiner.set_constraint(Constraint::triangle_budget(3000));
    refiner.run_to_convergence();
    EXPECT_GE(refiner.stats().triangles, 2999u);
    EXPECT_GT(refiner.counters().splits, splits);
}

TEST(Refiner, error_bounds_refine_and_raised_bounds_coarsen) {
    auto field = spheroid();
    RefineSettings s;
    s.error_measure = make_error_measure("epsilon4");
    s.constraint = Constraint::max_error(1e-4) && Constraint::triangle_budget(200000);
    Refiner refiner(field, test::cube_sphere_mesh(*field, 3), s);
    refiner.run_to_convergence();
    const MeshStats fine = refiner.stats();
    EXPECT_LE(fine.max_error, 1e-4);
    EXPECT_GT(fine.triangles, 500u);
    refiner.set_constraint(Constraint::max_error(1e-3));
    const StepResult r = refiner.run_to_convergence();
    EXPECT_GT(r.merges, 0u);
    const MeshStats coarse = refiner.stats();
    EXPECT_LE(coarse.max_error, 1e-3);
    EXPECT_LT(coarse.triangles, fine.triangles);

    refiner.set_constraint(Constraint::total_error(0.05));
    refiner.run_to_convergence();
    EXPECT_LE(refiner.stats().total_error, 0.05);
    EXPECT_EQ(check_conforming(refiner.mesh().mesh), "");
}

TEST(Refiner, statistics_match_a_recount) {
    auto field = spheroid();
    RefineSettings settings = budget_settings(3000);
    settings.error_measure = make_error_measure("epsilon4");
    Refiner refiner(field, test::cube_sphere_mesh(*field, 3), settings);
    refiner.run_to_convergence();
    refiner.set_constraint(Constraint::triangle_budget(1000));
    refiner.run_to_convergence();
    const RefinedMesh m = refiner.mesh();
    auto e = field->make_evaluator();
    Epsilon4Error measure;
    double total = 0.0, max = 0.0;
    for (std::size_t t = 0; t < m.mesh.triangles.size(); ++t) {
        const int b = m.mesh.base_edge[t];
        const auto& tri = m.mesh.triangles[t];
        TriangleGeometry g{m.mesh.positions[tri[b]],
                           m.mesh.positions[tri[(b + 1) % 3]],
                           m.mesh.positions[tri[(b + 2) % 3]],
                           {}};
        // The refiner's own search line; the point found agrees to the projection tolerance.
        g.projected_midpoint =
            project_to_surface(
                *e, {0.5 * (g.a + g.b), m.mesh.normals[tri[b]] + m.mesh.normals[tri[(b + 1) % 3]],
                     0.0, glm::length(g.b - g.a), 0})
                .position;
        const double err = measure.triangle_error(*e, g);
        total += err;
        max = std::max(max, err);
    }
    const MeshStats s = refiner.stats();
    EXPECT_EQ(s.triangles, m.mesh.triangles.size());
    EXPECT_NEAR(s.total_error, total, 1e-6 * total);
    EXPECT_NEAR(s.max_error, max, 1e-6 * max);
}

TEST(Refiner, rejects_bad_input_with_a_message) {
    auto field = spheroid();
    Mesh broken = test::cube_sphere_mesh(*field, 2);
    broken.triangles[0][1] = 100000;
    EXPECT_THROW(Refiner(field, broken, {}), std::invalid_argument);
    Mesh flipped = test::cube_sphere_mesh(*field, 2);
    std::swap(flipped.triangles[0][0], flipped.triangles[0][1]);
    EXPECT_NE(validate_refinable(flipped), "");
    Mesh nan_mesh = test::cube_sphere_mesh(*field, 2);
    nan_mesh.positions[0].x = std::nan("");
    EXPECT_NE(validate_refinable(nan_mesh), "");
    Mesh doubled = test::cube_sphere_mesh(*field, 2);
    doubled.triangles.push_back(doubled.triangles[0]);
    EXPECT_NE(validate_refinable(doubled), "");
    EXPECT_THROW(Refiner(nullptr, test::cube_sphere_mesh(*field, 2), {}), std::invalid_argument);
    RefineSettings bad_ratio;
    bad_ratio.swap_ratio = 1.0;
    EXPECT_THROW(Refiner(field, test::cube_sphere_mesh(*field, 2), bad_ratio),
                 std::invalid_argument);
    // An empty mesh is valid and stays empty.
    Refiner empty(field, Mesh{}, budget_settings(100));
    EXPECT_TRUE(empty.step({10}).converged);
    EXPECT_EQ(empty.stats().triangles, 0u);
}

TEST(Refiner, cancellation_and_time_budgets_stop_a_step) {
    auto field = spheroid();
    std::atomic<bool> cancel{true};
    RefineSettings s = budget_settings(100000);
    s.cancel = &cancel;
    Refiner refiner(field, test::cube_sphere_mesh(*field, 3), s);
    const StepResult r = refiner.step({1000});
    EXPECT_TRUE(r.cancelled);
    EXPECT_EQ(r.splits, 0u);
    cancel = false;
    const StepResult timed = refiner.step({1u << 30, WorkBudget(1000, WorkBudget::wall_clock())});
    EXPECT_FALSE(timed.converged);
    EXPECT_GT(timed.splits, 0u);
    EXPECT_LT(refiner.stats().triangles, 100000u);
}

// A function undefined around a pole: no vertex is ever placed where f is not finite.
TEST(Refiner, singular_functions_leave_vertices_on_the_mesh) {
    // The unit sphere with a pole at the north pole's height: f = |p|^2 - 1 + 0.01 / (z - 1.2).
    auto field = test::make_analytic_field(
        {[](const glm::dvec3& p) { return glm::dot(p, p) - 1.0 + 0.01 / (p.z - 1.2); },
         [](const glm::dvec3& p) {
             return 2.0 * p - glm::dvec3(0, 0, 0.01 / ((p.z - 1.2) * (p.z - 1.2)));
         }});
    RefineSettings s = budget_settings(3000);
    Refiner refiner(field, test::cube_sphere_mesh(*field, 2), s);
    run_checked(refiner, 200);
    auto e = field->make_evaluator();
    for (const glm::dvec3& p : refiner.mesh().mesh.positions) {
        ASSERT_TRUE(std::isfinite(e->value(p)));
        ASSERT_LT(p.z, 1.2);
    }
}

}  // namespace
}  // namespace isomesh
