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

// take() indexes the ids' range when the ids are close together and sorts them when they are far
// apart (a long session's old and new ids): both give the same net changes.
TEST(DeltaBuilder, far_apart_ids_net_as_close_ones) {
    auto log = [](std::uint32_t spread) {
        DeltaBuilder b;
        for (std::uint32_t i = 0; i < 50; ++i) {
            const std::uint32_t id = (i * 7 % 50) * spread;
            b.add_vertex(vertex(id, i));
            if (i % 3 == 0) b.move_vertex(vertex(id, i + 0.5));
            if (i % 5 == 0) b.remove_vertex(id);
            b.remove_triangle(id + 1);
            if (i % 2 == 0) b.add_triangle({id + 1, {id, 0, 1}});
            b.add_triangle({id + 2, {id, 1, 2}});
        }
        return b.take();
    };
    const MeshDelta close = log(3);
    const MeshDelta far = log(10'000'000);
    auto scaled = [](std::uint32_t id) { return id / 3 * 10'000'000 + id % 3; };
    ASSERT_EQ(far.removed_triangles.size(), close.removed_triangles.size());
    for (std::size_t i = 0; i < close.removed_triangles.size(); ++i)
        EXPECT_EQ(far.removed_triangles[i], scaled(close.removed_triangles[i]));
    ASSERT_EQ(far.added_triangles.size(), close.added_triangles.size());
    for (std::size_t i = 0; i < close.added_triangles.size(); ++i)
        EXPECT_EQ(far.added_triangles[i].id, scaled(close.added_triangles[i].id));
    ASSERT_EQ(far.added_vertices.size(), close.added_vertices.size());
    for (std::size_t i = 0; i < close.added_vertices.size(); ++i) {
        EXPECT_EQ(far.added_vertices[i].id, scaled(close.added_vertices[i].id));
        EXPECT_EQ(far.added_vertices[i].position, close.added_vertices[i].position);
    }
    EXPECT_TRUE(far.removed_vertices.empty() && close.removed_vertices.empty());
    EXPECT_EQ(close.added_vertices.size(), 40u);     // 10 of 50 removed
    EXPECT_EQ(close.removed_triangles.size(), 25u);  // odd i: removed, not restored
    EXPECT_EQ(close.added_triangles.size(), 50u);    // every id + 2
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
