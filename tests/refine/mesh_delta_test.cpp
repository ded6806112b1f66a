#include "refine/mesh_delta.h"

#include <gtest/gtest.h>

namespace isomesh {
namespace {

DeltaVertex vertex(std::uint32_t id, double x) {
    return {id, {x, 0, 0}, {0, 0, 1}};
}

TEST(DeltaBuilder, opposite_changes_cancel_out) {
    DeltaBuilder b;
    b.add_vertex(vertex(5, 1));
    b.remove_vertex(5);  // created and removed in the same step
    b.add_triangle({10, {0, 1, 2}});
    b.remove_triangle(10);
    b.remove_triangle(11);  // removed (split) and restored (merged)
    b.add_triangle({11, {0, 1, 3}});
    EXPECT_TRUE(b.take().empty());
}

TEST(DeltaBuilder, moves_fold_into_additions_and_lists_are_sorted) {
    DeltaBuilder b;
    b.add_vertex(vertex(9, 1));
    b.move_vertex(vertex(9, 2));
    b.move_vertex(vertex(3, 5));
    b.move_vertex(vertex(3, 6));
    b.remove_vertex(7);
    b.remove_vertex(2);
    b.add_triangle({20, {9, 3, 4}});
    b.add_triangle({19, {9, 4, 3}});
    const MeshDelta d = b.take();
    ASSERT_EQ(d.added_vertices.size(), 1u);
    EXPECT_EQ(d.added_vertices[0].position.x, 2.0);
    ASSERT_EQ(d.moved_vertices.size(), 1u);
    EXPECT_EQ(d.moved_vertices[0].position.x, 6.0);
    EXPECT_EQ(d.removed_vertices, (std::vector<std::uint32_t>{2, 7}));
    ASSERT_EQ(d.added_triangles.size(), 2u);
    EXPECT_EQ(d.added_triangles[0].id, 19u);
    EXPECT_TRUE(b.take().empty());  // take() resets
}

TEST(DeltaMesh, applies_in_order_and_reports_inconsistencies) {
    DeltaMesh mesh;
    MeshDelta first;
    first.added_vertices = {vertex(0, 0), vertex(1, 1), vertex(2, 2)};
    first.added_triangles = {{0, {0, 1, 2}}};
    EXPECT_EQ(mesh.apply(first), "");
    EXPECT_EQ(mesh.triangle_count(), 1u);

    MeshDelta remove_used;
    remove_used.removed_vertices = {1};
    EXPECT_NE(mesh.apply(remove_used), "");

    DeltaMesh other;
    EXPECT_NE(other.apply(MeshDelta{{7}, {}, {}, {}, {}}), "");  // unknown triangle
    MeshDelta unknown_vertex;
    unknown_vertex.added_triangles = {{0, {0, 1, 2}}};
    EXPECT_NE(other.apply(unknown_vertex), "");

    MeshDelta second;
    second.removed_triangles = {0};
    second.removed_vertices = {2};
    second.added_vertices = {vertex(3, 3)};
    second.moved_vertices = {vertex(0, -1)};
    second.added_triangles = {{1, {0, 1, 3}}};
    DeltaMesh fresh;
    ASSERT_EQ(fresh.apply(first), "");
    ASSERT_EQ(fresh.apply(second), "");
    const Mesh m = fresh.to_mesh();
    ASSERT_EQ(m.positions.size(), 3u);
    EXPECT_EQ(m.positions[0].x, -1.0);
    EXPECT_EQ(m.positions[2].x, 3.0);
    EXPECT_EQ(m.triangles, (std::vector<std::array<std::uint32_t, 3>>{{0, 1, 2}}));
    EXPECT_EQ(fresh.triangle_ids(), (std::vector<std::uint32_t>{1}));
}

}  // namespace
}  // namespace isomesh
