#include "polygonize/thin_triangle_cleanup.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "mesh/topology.h"

namespace isomesh {
namespace {

/// An n x n grid of unit squares in the plane z = 0, two triangles each, facing +z; vertices on
/// the square's border are marked as lying on the faces x = 0, x = n, y = 0, y = n of a box.
struct Grid {
    Mesh mesh;
    std::vector<std::uint8_t> faces;
};

Grid plane_grid(int n) {
    Grid g;
    for (int j = 0; j <= n; ++j) {
        for (int i = 0; i <= n; ++i) {
            g.mesh.positions.push_back({i, j, 0.0});
            g.mesh.normals.push_back({0.0, 0.0, 1.0});
            std::uint8_t f = 0;
            if (i == 0) f |= 1;
            if (i == n) f |= 2;
            if (j == 0) f |= 4;
            if (j == n) f |= 8;
            g.faces.push_back(f);
        }
    }
    auto id = [n](int i, int j) { return static_cast<std::uint32_t>(i + (n + 1) * j); };
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            g.mesh.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
            g.mesh.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
        }
    }
    return g;
}

std::size_t thin_count(const Mesh& mesh, double min_quality) {
    std::size_t n = 0;
    for (const auto& t : mesh.triangles) {
        n += triangle_quality(mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]) <
             min_quality;
    }
    return n;
}

TEST(ThinTriangleCleanup, collapses_a_vertex_next_to_another) {
    Grid g = plane_grid(4);
    g.mesh.positions[12] = {2.0 + 1e-9, 2.0 + 1e-9, 0.0};  // centre vertex (2, 2) moved
    g.mesh.positions[13] = {2.0, 2.0, 0.0};                // (3, 2) onto it: needles
    const long chi = analyze_topology(g.mesh).euler_characteristic;
    const ThinTriangleReport report = remove_thin_triangles(g.mesh, g.faces, {0.1, 0.1});
    EXPECT_GE(report.collapses, 1u);
    EXPECT_EQ(report.remaining_degenerate, 0u);
    const TopologyReport after = analyze_topology(g.mesh);
    EXPECT_EQ(after.euler_characteristic, chi);
    EXPECT_EQ(after.degenerate_triangles, 0u);
    EXPECT_TRUE(after.manifold());
    EXPECT_EQ(after.inconsistently_oriented_edges, 0u);
    EXPECT_EQ(g.mesh.vertex_count(), 24u);
    EXPECT_EQ(thin_count(g.mesh, 0.1), report.remaining_thin);
}

TEST(ThinTriangleCleanup, flips_a_cap) {
    Grid g = plane_grid(2);
    // The centre (1, 1) moved next to the middle of edge (1, 0)-(2, 1): triangle
    // (1, 0) (2, 1) centre becomes a cap (an angle near 180 degrees), no edge of it short.
    g.mesh.positions[4] = {1.5, 0.52, 0.0};
    const ThinTriangleReport report = remove_thin_triangles(g.mesh, g.faces, {0.0, 0.1});
    EXPECT_GE(report.flips + report.collapses, 1u);
    EXPECT_EQ(thin_count(g.mesh, 0.1), report.remaining_thin);
    EXPECT_TRUE(analyze_topology(g.mesh).manifold());
}

TEST(ThinTriangleCleanup, keeps_vertices_on_the_box_faces) {
    Grid g = plane_grid(3);
    g.mesh.positions[1] = {1e-6, 0.0, 0.0};  // (1, 0) on face y = 0 slides next to corner (0, 0)
    const std::vector<glm::dvec3> border_before = {g.mesh.positions[0], g.mesh.positions[3]};
    remove_thin_triangles(g.mesh, g.faces, {0.1, 0.1});
    // The corner (on two faces) must survive; the border stays a closed loop on the faces.
    EXPECT_EQ(g.mesh.positions[0], border_before[0]);
    const TopologyReport after = analyze_topology(g.mesh);
    EXPECT_EQ(after.euler_characteristic, 1);
    EXPECT_EQ(after.degenerate_triangles, 0u);
    for (std::size_t v = 0; v < g.mesh.vertex_count(); ++v) {
        const glm::dvec3& p = g.mesh.positions[v];
        EXPECT_TRUE(p.x == 0.0 || p.x == 3.0 || p.y == 0.0 || p.y == 3.0 ||
                    (p.x > 0.5 && p.x < 2.5 && p.y > 0.5 && p.y < 2.5))
            << "vertex " << v << " left the border";
    }
}

TEST(ThinTriangleCleanup, triangle_quality_is_one_for_equilateral_and_zero_when_flat) {
    EXPECT_NEAR(triangle_quality({0, 0, 0}, {1, 0, 0}, {0.5, std::sqrt(0.75), 0.0}), 1.0, 1e-15);
    EXPECT_EQ(triangle_quality({0, 0, 0}, {1, 0, 0}, {2, 0, 0}), 0.0);
    EXPECT_EQ(triangle_quality({1, 1, 1}, {1, 1, 1}, {1, 1, 1}), 0.0);
}

}  // namespace
}  // namespace isomesh
