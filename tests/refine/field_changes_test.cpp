// Function versions (set_field, reset): the refined mesh follows a changing function. (Whether
// the topology changed is the pipeline's to decide: tests/progressive.)
#include <cmath>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "fixtures.h"
#include "mesh/topology.h"
#include "polygonize/polygonizer.h"
#include "refine/refiner.h"

namespace isomesh {
namespace {

std::shared_ptr<const Field> sphere_a(double a) {
    return test::make_quadric_field({1, 1, 1}, a);
}

RefineSettings sphere_settings(std::size_t budget) {
    RefineSettings s;
    s.constraint = Constraint::triangle_budget(budget);
    return s;
}

Refiner sphere_refiner(double a, const RefineSettings& settings) {
    auto field = sphere_a(a);
    return Refiner(field, test::cube_sphere_mesh(*field, 3), settings);
}

double max_distance_to_sphere(const Mesh& mesh, double radius) {
    double worst = 0.0;
    for (const glm::dvec3& p : mesh.positions)
        worst = std::max(worst, std::abs(glm::length(p) - radius));
    return worst;
}

TEST(RefinerVersions, fifty_parameter_changes_end_like_a_fresh_mesh) {
    const RefineSettings settings = sphere_settings(3000);
    Refiner refiner = sphere_refiner(1.0, settings);
    refiner.run_to_convergence();
    std::vector<MeshDelta> deltas;
    const MeshDelta start = refiner.snapshot();
    for (int i = 1; i <= 50; ++i) {
        const double a = 1.0 + 19.0 * i / 50.0;
        refiner.set_field(sphere_a(a));
        // A slider moves faster than the mesh converges: only part of the work between changes.
        deltas.push_back(refiner.step({1500}).delta);
        EXPECT_EQ(test::check_conforming(refiner.mesh().mesh), "") << "a = " << a;
    }
    deltas.push_back(refiner.run_to_convergence().delta);
    EXPECT_EQ(refiner.version(), 51u);
    EXPECT_EQ(refiner.counters().restarts, 0u);

    Refiner fresh = sphere_refiner(20.0, settings);
    fresh.run_to_convergence();

    const RefinedMesh changed = refiner.mesh();
    const RefinedMesh reference = fresh.mesh();
    const TopologyReport t1 = analyze_topology(changed.mesh), t2 = analyze_topology(reference.mesh);
    EXPECT_EQ(t1.components, t2.components);
    EXPECT_EQ(t1.euler_characteristic, t2.euler_characteristic);
    EXPECT_TRUE(t1.watertight());
    EXPECT_NEAR(double(changed.mesh.triangles.size()), double(reference.mesh.triangles.size()),
                1.0);
    // Every vertex is on the new sphere.
    EXPECT_LT(max_distance_to_sphere(changed.mesh, std::sqrt(20.0)), 1e-8);

    auto e1 = sphere_a(20.0)->make_evaluator();
    const MeshErrorReport r1 = measure_mesh_error(changed.mesh, *e1);
    const MeshErrorReport r2 = measure_mesh_error(reference.mesh, *e1);
    std::printf("after 50 changes: eps4 total %.5f max distance %.5f; fresh: %.5f %.5f\n",
                r1.epsilon4_total, r1.max_distance, r2.epsilon4_total, r2.max_distance);
    EXPECT_NEAR(r1.epsilon4_total, r2.epsilon4_total, 0.1 * r2.epsilon4_total);
    EXPECT_NEAR(r1.max_distance, r2.max_distance, 0.25 * r2.max_distance);
    EXPECT_NEAR(refiner.stats().total_error, fresh.stats().total_error,
                0.1 * fresh.stats().total_error);
    EXPECT_NEAR(refiner.stats().max_error, fresh.stats().max_error, 0.25 * fresh.stats().max_error);

    // The client's copy, updated by deltas only, ends identical.
    std::string error;
    const Mesh replayed = test::replay_mesh(start, deltas, &error);
    EXPECT_EQ(error, "");
    EXPECT_TRUE(test::same_mesh(replayed, test::canonical(changed)));
}

// Moving vertices along a changed function is all a new version needs when the change is small.
TEST(RefinerVersions, a_small_change_moves_vertices_without_restarting) {
    Refiner refiner = sphere_refiner(4.0, sphere_settings(2000));
    refiner.run_to_convergence();
    const RefinedMesh before = refiner.mesh();
    refiner.set_field(sphere_a(4.2));
    const StepResult r = refiner.run_to_convergence();
    EXPECT_FALSE(r.restarted);
    EXPECT_EQ(
        r.delta.moved_vertices.size() + r.delta.added_vertices.size() >= before.vertex_ids.size(),
        true);
    EXPECT_LT(max_distance_to_sphere(refiner.mesh().mesh, std::sqrt(4.2)), 1e-8);
    EXPECT_EQ(refiner.counters().refreshed_vertices, before.vertex_ids.size());
}

TEST(RefinerVersions, field_change_pending_until_the_last_vertex_and_error_is_refreshed) {
    Refiner refiner = sphere_refiner(4.0, sphere_settings(2000));
    refiner.run_to_convergence();
    EXPECT_FALSE(refiner.field_change_pending());
    refiner.set_field(sphere_a(4.2));
    EXPECT_TRUE(refiner.field_change_pending());
    // Small steps: the flag drops in the step that refreshes the last item, not a step later.
    std::size_t refreshed = 0;
    while (refiner.field_change_pending()) {
        const StepResult r = refiner.step(StepBudget{64});
        ASSERT_GT(r.refreshed, 0u) << "a step while pending refreshes something";
        refreshed += r.refreshed;
    }
    EXPECT_EQ(refiner.counters().refreshed_vertices, refiner.mesh().vertex_ids.size());
    EXPECT_LT(max_distance_to_sphere(refiner.mesh().mesh, std::sqrt(4.2)), 1e-8);
    EXPECT_GE(refreshed, refiner.mesh().vertex_ids.size() + refiner.mesh().triangle_ids.size());
}

// Two spheres that merge into one: the topology of the phase-1 mesh changes, so the refiner starts
// again from it.
Mesh translated(Mesh mesh, const glm::dvec3& offset) {
    for (auto& p : mesh.positions) p += offset;
    return mesh;
}

Mesh joined(const Mesh& a, const Mesh& b) {
    Mesh m = a;
    const auto offset = static_cast<std::uint32_t>(a.positions.size());
    m.positions.insert(m.positions.end(), b.positions.begin(), b.positions.end());
    m.normals.insert(m.normals.end(), b.normals.begin(), b.normals.end());
    for (auto t : b.triangles) m.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
    return m;
}

std::shared_ptr<const Field> two_spheres(double d) {
    auto dist = [d](const glm::dvec3& p) {
        return std::min(glm::length(p - glm::dvec3(d, 0, 0)),
                        glm::length(p + glm::dvec3(d, 0, 0))) -
               1.0;
    };
    return test::make_analytic_field(
        {dist, [d](const glm::dvec3& p) {
             const glm::dvec3 a = p - glm::dvec3(d, 0, 0), b = p + glm::dvec3(d, 0, 0);
             return glm::length(a) < glm::length(b) ? glm::normalize(a) : glm::normalize(b);
         }});
}

TEST(RefinerVersions, reset_replaces_the_mesh_with_ids_continuing) {
    // Two balls apart (d = 3), then one star-shaped blob (d = 0.5): the owner of the refiner
    // sees the topology change and resets it with the new function's phase-1 mesh.
    RefineSettings s;
    s.constraint = Constraint::triangle_budget(1500);
    auto unit = test::make_sphere_field({0, 0, 0}, 1.0);
    const Mesh ball = test::cube_sphere_mesh(*unit, 3);
    Refiner refiner(two_spheres(3.0),
                    joined(translated(ball, {3.0, 0, 0}), translated(ball, {-3.0, 0, 0})), s);
    refiner.run_to_convergence();
    EXPECT_EQ(analyze_topology(refiner.mesh().mesh).components, 2u);
    EXPECT_EQ(refiner.root_topology().components, 2u);
    const MeshDelta start = refiner.snapshot();

    const auto blob = two_spheres(0.5);
    refiner.set_field(blob);
    refiner.reset(test::cube_sphere_mesh(*blob, 3));
    EXPECT_EQ(refiner.root_topology().components, 1u);
    const StepResult r = refiner.run_to_convergence();
    EXPECT_TRUE(r.restarted);
    EXPECT_EQ(refiner.counters().restarts, 1u);
    const RefinedMesh m = refiner.mesh();
    const TopologyReport report = analyze_topology(m.mesh);
    EXPECT_EQ(report.components, 1u);
    EXPECT_EQ(report.euler_characteristic, 2);
    EXPECT_TRUE(report.watertight());
    EXPECT_GE(m.mesh.triangles.size(), 1499u);
    // Ids of the new mesh continue after the old ones, and the delta replaces everything.
    std::string error;
    EXPECT_TRUE(test::same_mesh(test::replay_mesh(start, {r.delta}, &error), test::canonical(m)));
    EXPECT_EQ(error, "");
    EXPECT_GT(m.triangle_ids.front(), start.added_triangles.back().id);
}

// The refiner only moves vertices; they stay put where no surface is near, and it says so.
TEST(RefinerVersions, vertices_out_of_reach_stay_and_are_reported) {
    RefineSettings s;
    s.constraint = Constraint::triangle_budget(500);
    auto field = sphere_a(1.0);
    Refiner refiner(field, test::cube_sphere_mesh(*field, 2), s);
    refiner.run_to_convergence();
    refiner.set_field(sphere_a(100.0));  // radius 10: far beyond the vertices' reach
    refiner.run_to_convergence();
    EXPECT_GT(refiner.counters().failed_refreshes, 0u);
    EXPECT_TRUE(refiner.refresh_failed());
    EXPECT_EQ(refiner.counters().restarts, 0u);
    EXPECT_EQ(test::check_conforming(refiner.mesh().mesh), "");
}

}  // namespace
}  // namespace isomesh

namespace isomesh {
namespace {

// A bump travelling over a sphere: detail has to move with it. Split and merge exchanges (ROAM's
// dual queues) keep the mesh optimal at its budget: no split that fits is worth more than
// swap_ratio times the cheapest merge, and the error ends close to a fresh mesh's.
TEST(RefinerVersions, exchanges_follow_a_moving_bump) {
    const std::string expression = "x^2+y^2+z^2-4-3exp(-8((x-a)^2+y^2+(z-1)^2))=0";
    RefineSettings settings;
    settings.constraint = Constraint::triangle_budget(6000);
    auto phase1 = [](const std::shared_ptr<const Field>& f) {
        PolygonizeSettings p;
        p.min_depth = 3;
        p.threads = 1;
        return polygonize(*f, p).mesh;
    };
    const auto first = test::compile_field(expression, {{"a", 1.5}});
    Refiner refiner(first, phase1(first), settings);
    refiner.run_to_convergence();
    for (double a : {1.0, 0.5, 0.0, -0.5, -1.0, -1.5}) {
        refiner.set_field(test::compile_field(expression, {{"a", a}}));
        const StepResult r = refiner.run_to_convergence();
        EXPECT_FALSE(r.restarted);
        const QueueEnds ends = refiner.queue_ends();
        // The bucket queue treats priorities within one bucket as equal, so the exchange rule
        // holds up to one bucket's relative width (2^(1/buckets_per_octave)).
        const double bucket_width = std::exp2(1.0 / BucketQueueSettings{}.buckets_per_octave);
        EXPECT_LE(ends.largest_split, settings.swap_ratio * bucket_width * ends.smallest_merge)
            << "a = " << a;
        EXPECT_GE(refiner.stats().triangles + 1, 6000u);
    }
    EXPECT_GT(refiner.counters().swaps, 20u);
    EXPECT_GT(refiner.counters().merges, refiner.counters().swaps);

    const auto last = test::compile_field(expression, {{"a", -1.5}});
    Refiner fresh(last, phase1(last), settings);
    fresh.run_to_convergence();
    EXPECT_NEAR(refiner.stats().max_error, fresh.stats().max_error, 0.15 * fresh.stats().max_error);
    auto e = last->make_evaluator();
    const MeshErrorReport moved = measure_mesh_error(refiner.mesh().mesh, *e);
    const MeshErrorReport reference = measure_mesh_error(fresh.mesh().mesh, *e);
    EXPECT_LT(moved.max_distance, 1.15 * reference.max_distance);
    EXPECT_LT(moved.epsilon4_total, 1.05 * reference.epsilon4_total);
}

}  // namespace
}  // namespace isomesh
