#include "mesh/topology.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace isomesh {
namespace {

/// A regular tetrahedron with outward counter-clockwise triangles.
Mesh tetrahedron() {
    Mesh mesh;
    mesh.positions = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
    mesh.triangles = {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}};
    return mesh;
}

/// A torus as an m x n quad grid with wrapped indices, each quad split in two.
Mesh torus(int m, int n) {
    Mesh mesh;
    for (int i = 0; i < m; ++i) {
        for (int j = 0; j < n; ++j) {
            const double u = 2 * M_PI * i / m, v = 2 * M_PI * j / n;
            mesh.positions.push_back(
                {(2 + std::cos(v)) * std::cos(u), (2 + std::cos(v)) * std::sin(u), std::sin(v)});
        }
    }
    const auto id = [n, m](int i, int j) {
        return static_cast<std::uint32_t>((i % m) * n + (j % n));
    };
    for (int i = 0; i < m; ++i) {
        for (int j = 0; j < n; ++j) {
            mesh.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
            mesh.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
        }
    }
    return mesh;
}

TEST(Topology, tetrahedron_is_a_closed_sphere) {
    const TopologyReport r = analyze_topology(tetrahedron());
    EXPECT_EQ(r.vertices, 4u);
    EXPECT_EQ(r.edges, 6u);
    EXPECT_EQ(r.triangles, 4u);
    EXPECT_EQ(r.components, 1u);
    EXPECT_EQ(r.euler_characteristic, 2);
    EXPECT_TRUE(r.watertight());
    EXPECT_TRUE(r.manifold());
    EXPECT_EQ(r.inconsistently_oriented_edges, 0u);
    EXPECT_EQ(r.degenerate_triangles, 0u);
    EXPECT_EQ(r.first_betti_number(), 0);
}

TEST(Topology, torus_has_first_betti_number_two) {
    const TopologyReport r = analyze_topology(torus(8, 6));
    EXPECT_TRUE(r.watertight());
    EXPECT_TRUE(r.manifold());
    EXPECT_EQ(r.euler_characteristic, 0);
    EXPECT_EQ(r.first_betti_number(), 2);
    EXPECT_EQ(r.inconsistently_oriented_edges, 0u);
}

TEST(Topology, signed_volume_is_positive_for_outward_triangles) {
    Mesh mesh = tetrahedron();
    EXPECT_NEAR(signed_volume(mesh), 8.0 / 3.0, 1e-12);  // the cube [-1, 1]^3 minus 4 corners
    for (auto& t : mesh.triangles) std::swap(t[1], t[2]);
    EXPECT_NEAR(signed_volume(mesh), -8.0 / 3.0, 1e-12);
}

TEST(Topology, components_and_unused_vertices) {
    Mesh mesh = tetrahedron();
    Mesh other = tetrahedron();
    mesh.positions.push_back({9, 9, 9});  // unused: not counted
    const std::uint32_t offset = static_cast<std::uint32_t>(mesh.positions.size());
    for (const auto& p : other.positions) mesh.positions.push_back(p + glm::dvec3(5, 0, 0));
    for (const auto& t : other.triangles)
        mesh.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
    const TopologyReport r = analyze_topology(mesh);
    EXPECT_EQ(r.vertices, 8u);
    EXPECT_EQ(r.components, 2u);
    EXPECT_EQ(r.euler_characteristic, 4);
}

TEST(Topology, open_disk_has_boundary_edges) {
    Mesh mesh = tetrahedron();
    mesh.triangles.pop_back();
    const TopologyReport r = analyze_topology(mesh);
    EXPECT_EQ(r.boundary_edges, 3u);
    EXPECT_FALSE(r.watertight());
    EXPECT_TRUE(r.manifold());
    EXPECT_EQ(r.euler_characteristic, 1);
}

TEST(Topology, flipped_triangle_is_inconsistently_oriented) {
    Mesh mesh = tetrahedron();
    std::swap(mesh.triangles[0][1], mesh.triangles[0][2]);
    EXPECT_EQ(analyze_topology(mesh).inconsistently_oriented_edges, 3u);
}

TEST(Topology, three_triangles_on_an_edge_are_not_manifold) {
    Mesh mesh = tetrahedron();
    mesh.positions.push_back({0, 0, -3});
    mesh.triangles.push_back({0, 1, 4});
    const TopologyReport r = analyze_topology(mesh);
    EXPECT_EQ(r.nonmanifold_edges, 1u);
    EXPECT_FALSE(r.manifold());
    EXPECT_FALSE(r.watertight());
}

TEST(Topology, two_fans_at_a_vertex_are_not_manifold) {
    Mesh mesh;
    mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
    mesh.triangles = {{0, 1, 2}, {0, 3, 4}};  // a bow tie touching at vertex 0
    const TopologyReport r = analyze_topology(mesh);
    EXPECT_EQ(r.nonmanifold_edges, 0u);
    EXPECT_EQ(r.nonmanifold_vertices, 1u);
    EXPECT_FALSE(r.manifold());
}

TEST(Topology, degenerate_triangles_are_counted) {
    Mesh mesh;
    mesh.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}};
    mesh.triangles = {{0, 1, 2}, {0, 0, 3}, {0, 1, 3}};  // collinear, repeated vertex, fine
    EXPECT_EQ(analyze_topology(mesh).degenerate_triangles, 2u);
}

TEST(Topology, out_of_range_index_is_an_error) {
    Mesh mesh = tetrahedron();
    mesh.triangles.push_back({0, 1, 7});
    EXPECT_THROW(analyze_topology(mesh), std::invalid_argument);
    EXPECT_THROW(build_adjacency(mesh), std::invalid_argument);
}

TEST(Adjacency, neighbours_are_mutual_across_shared_edges) {
    Mesh mesh = torus(7, 5);
    build_adjacency(mesh);
    ASSERT_EQ(mesh.neighbours.size(), mesh.triangles.size());
    for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
        for (int e = 0; e < 3; ++e) {
            const std::uint32_t u = mesh.neighbours[t][e];
            ASSERT_NE(u, kNoNeighbour);
            const std::uint32_t a = mesh.triangles[t][e], b = mesh.triangles[t][(e + 1) % 3];
            int back = -1;
            for (int f = 0; f < 3; ++f) {
                if (mesh.triangles[u][f] == b && mesh.triangles[u][(f + 1) % 3] == a) back = f;
            }
            ASSERT_GE(back, 0) << "triangle " << t << " edge " << e;
            EXPECT_EQ(mesh.neighbours[u][back], t);
        }
    }
}

TEST(Adjacency, boundary_edges_have_no_neighbour) {
    Mesh mesh = tetrahedron();
    mesh.triangles.pop_back();
    build_adjacency(mesh);
    int boundary = 0;
    for (const auto& n : mesh.neighbours) {
        for (std::uint32_t u : n) boundary += u == kNoNeighbour ? 1 : 0;
    }
    EXPECT_EQ(boundary, 3);
}

TEST(Adjacency, base_edge_is_the_longest) {
    Mesh mesh;
    mesh.positions = {{0, 0, 0}, {4, 0, 0}, {0, 1, 0}, {1, 1, 0}};
    mesh.triangles = {{0, 1, 2}, {3, 2, 1}};  // (1, 2) has length sqrt(17) > 4 > sqrt(10)
    build_adjacency(mesh);
    EXPECT_EQ(mesh.base_edge[0], 1);
    EXPECT_EQ(mesh.base_edge[1], 1);
}

TEST(Adjacency, tied_edges_rank_by_vertex_indices_whatever_the_rotation) {
    // Legs (0, 2) and (1, 2) both have length sqrt(26); (0, 2) wins in every rotation.
    const std::array<std::array<std::uint32_t, 3>, 3> rotations{{{2, 0, 1}, {0, 1, 2}, {1, 2, 0}}};
    const std::array<std::uint8_t, 3> expected{0, 2, 1};
    for (int r = 0; r < 3; ++r) {
        Mesh mesh;
        mesh.positions = {{0, 0, 0}, {2, 0, 0}, {1, 5, 0}};
        mesh.triangles = {rotations[r]};
        build_adjacency(mesh);
        EXPECT_EQ(mesh.base_edge[0], expected[r]) << "rotation " << r;
    }
}

TEST(Adjacency, nonmanifold_edge_is_an_error) {
    Mesh mesh = tetrahedron();
    mesh.positions.push_back({0, 0, -3});
    mesh.triangles.push_back({0, 1, 4});
    EXPECT_THROW(build_adjacency(mesh), std::invalid_argument);
}

}  // namespace
}  // namespace isomesh
