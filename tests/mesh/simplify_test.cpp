// Simplification to a triangle budget (mesh/simplify.h) on phase-1 meshes of closed surfaces.
#include "mesh/simplify.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "mesh/topology.h"
#include "polygonize/polygonizer.h"
#include "support/mesh_checks.h"

namespace isomesh {
namespace {

/// A closed genus-2 surface well inside its box: no vertex on a box face.
Mesh genus_two_mesh() {
    const auto field = test::field_of("((x^2+y^2)^2-x^2+y^2)^2+z^2=0.01");
    PolygonizeSettings settings;
    settings.box = {{-1.5, -1.0, -0.5}, {1.5, 1.0, 0.5}};
    settings.min_depth = 4;
    settings.max_depth = 7;
    return polygonize(*field, settings).mesh;
}

TEST(Simplify, simplify_to_budget_keeps_topology_and_meets_the_target) {
    Mesh mesh = genus_two_mesh();
    const TopologyReport before = analyze_topology(mesh);
    ASSERT_GT(before.triangles, 2000u);
    const std::vector<std::uint8_t> faces(mesh.vertex_count(), 0);
    const SimplifyReport report = simplify_to_budget(mesh, faces, 1000);
    EXPECT_TRUE(report.reached);
    EXPECT_LE(mesh.triangle_count(), 1000u);
    EXPECT_EQ(report.triangles, mesh.triangle_count());
    const TopologyReport after = analyze_topology(mesh);
    EXPECT_EQ(after.components, before.components);
    EXPECT_EQ(after.euler_characteristic, before.euler_characteristic);
    EXPECT_TRUE(after.manifold());
}

TEST(Simplify, simplify_to_budget_ends_with_a_vertex_at_no_finite_point) {
    Mesh mesh = genus_two_mesh();
    mesh.positions[mesh.vertex_count() / 2] = glm::dvec3(std::nan(""), 0.0, 0.0);
    const std::vector<std::uint8_t> faces(mesh.vertex_count(), 0);
    // Its collapse costs are NaN: ordered last, not popped and pushed back forever.
    const SimplifyReport report = simplify_to_budget(mesh, faces, 1000);
    EXPECT_TRUE(report.reached);
    EXPECT_LE(mesh.triangle_count(), 1000u);
}

/// A budget of one unit on a clock that ticks at each look: a few hundred candidates a slice.
WorkBudget one_tick(const std::shared_ptr<std::int64_t>& ticks) {
    return WorkBudget(*ticks + 1, [ticks] { return (*ticks)++; });
}

/// Simplifies the genus-2 mesh towards `target` in slices and in one call: the same mesh.
void expect_slices_give_the_mesh_of_one_call(SimplifyTarget target) {
    Mesh whole = genus_two_mesh();
    const std::vector<std::uint8_t> faces(whole.vertex_count(), 0);
    Simplification sliced(whole, faces, target);
    const SimplifyReport one_call = simplify_to_budget(whole, faces, target);
    auto ticks = std::make_shared<std::int64_t>(0);
    int slices = 0;
    for (; !sliced.done(); ++slices) {
        sliced.advance(one_tick(ticks));
        ASSERT_LT(slices, 1000000);
    }
    EXPECT_GT(slices, 3);  // it was sliced
    EXPECT_EQ(sliced.report().reached, one_call.reached);
    EXPECT_EQ(sliced.report().reached_preferred, one_call.reached_preferred);
    const Mesh result = sliced.take();
    EXPECT_EQ(result.positions, whole.positions);
    EXPECT_EQ(result.triangles, whole.triangles);
}

TEST(Simplification, advance_in_slices_gives_the_mesh_of_one_call) {
    expect_slices_give_the_mesh_of_one_call(1000);
}

TEST(Simplification, advance_in_slices_to_a_preferred_count_gives_the_mesh_of_one_call) {
    expect_slices_give_the_mesh_of_one_call({1000, 600});
}

TEST(Simplification, advance_in_slices_below_the_topologys_floor_gives_the_mesh_of_one_call) {
    expect_slices_give_the_mesh_of_one_call({1000, 2});
}

TEST(Simplification, advance_stops_when_cancelled_and_reports_it) {
    Mesh mesh = genus_two_mesh();
    Simplification s(mesh, std::vector<std::uint8_t>(mesh.vertex_count(), 0), 1000);
    std::atomic<bool> cancel{true};
    EXPECT_FALSE(s.advance(WorkBudget(&cancel)));
    EXPECT_TRUE(s.report().cancelled);
    EXPECT_FALSE(s.done());
}

TEST(Simplify, simplify_to_budget_goes_on_to_the_preferred_count_where_the_topology_allows) {
    Mesh mesh = genus_two_mesh();
    const TopologyReport before = analyze_topology(mesh);
    const std::vector<std::uint8_t> faces(mesh.vertex_count(), 0);
    const SimplifyReport report = simplify_to_budget(mesh, faces, {1000, 500});
    EXPECT_TRUE(report.reached);
    EXPECT_TRUE(report.reached_preferred);
    EXPECT_LE(mesh.triangle_count(), 500u);
    EXPECT_GT(mesh.triangle_count(), 490u);  // collapses remove two triangles at a time
    const TopologyReport after = analyze_topology(mesh);
    EXPECT_EQ(after.euler_characteristic, before.euler_characteristic);
    EXPECT_TRUE(after.manifold());
}

TEST(Simplify, simplify_to_budget_keeps_the_mesh_at_the_limit_below_the_topologys_floor) {
    Mesh at_limit = genus_two_mesh();
    Mesh floor = at_limit;
    const std::vector<std::uint8_t> faces(at_limit.vertex_count(), 0);
    simplify_to_budget(at_limit, faces, 1000);
    // A genus-2 surface needs more than 2 triangles: the preferred count is out of reach.
    const SimplifyReport report = simplify_to_budget(floor, faces, {1000, 2});
    EXPECT_TRUE(report.reached);
    EXPECT_FALSE(report.reached_preferred);
    EXPECT_GT(report.collapses, 0u);
    EXPECT_EQ(report.triangles, floor.triangle_count());
    EXPECT_EQ(floor.positions, at_limit.positions);
    EXPECT_EQ(floor.triangles, at_limit.triangles);
}

TEST(Simplification, take_before_done_gives_the_mesh_at_the_limit_once_reached) {
    Mesh mesh = genus_two_mesh();
    const std::vector<std::uint8_t> faces(mesh.vertex_count(), 0);
    Simplification s(mesh, faces, {1000, 2});
    // Slices until the limit is reached: it is then on its way to the floor.
    auto ticks = std::make_shared<std::int64_t>(0);
    for (int i = 0; i < 1000000 && !s.done() && !s.report().reached; ++i)
        s.advance(one_tick(ticks));
    ASSERT_TRUE(s.report().reached);
    ASSERT_FALSE(s.done());
    const Mesh taken = s.take();
    EXPECT_LE(taken.triangle_count(), 1000u);
    EXPECT_EQ(s.report().triangles, taken.triangle_count());
    EXPECT_TRUE(analyze_topology(taken).manifold());
}

}  // namespace
}  // namespace isomesh
