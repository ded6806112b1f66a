// Simplification to a triangle budget (mesh/simplify.h) on phase-1 meshes of closed surfaces.
#include "mesh/simplify.h"

#include <gtest/gtest.h>

#include <atomic>
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

TEST(Simplification, advance_in_slices_gives_the_mesh_of_one_call) {
    Mesh whole = genus_two_mesh();
    const std::vector<std::uint8_t> faces(whole.vertex_count(), 0);
    Simplification sliced(whole, faces, 1000);
    simplify_to_budget(whole, faces, 1000);
    // Budgets of one unit on a clock that ticks at each look: a few hundred candidates a slice.
    auto ticks = std::make_shared<std::int64_t>(0);
    int slices = 0;
    for (; !sliced.done(); ++slices) {
        sliced.advance(WorkBudget(*ticks + 1, [ticks] { return (*ticks)++; }));
        ASSERT_LT(slices, 1000000);
    }
    EXPECT_GT(slices, 3);  // it was sliced
    EXPECT_TRUE(sliced.report().reached);
    const Mesh result = sliced.take();
    EXPECT_EQ(result.positions, whole.positions);
    EXPECT_EQ(result.triangles, whole.triangles);
}

TEST(Simplification, advance_stops_when_cancelled_and_reports_it) {
    Mesh mesh = genus_two_mesh();
    Simplification s(mesh, std::vector<std::uint8_t>(mesh.vertex_count(), 0), 1000);
    std::atomic<bool> cancel{true};
    EXPECT_FALSE(s.advance(WorkBudget(&cancel)));
    EXPECT_TRUE(s.report().cancelled);
    EXPECT_FALSE(s.done());
}

}  // namespace
}  // namespace isomesh
