#include "support/mesh_checks.h"

#include <cmath>
#include <map>
#include <utility>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "eval/tape_field.h"
#include "expr/compile.h"
#include "expr/function_source.h"

namespace isomesh::test {

std::shared_ptr<const Field> field_of(std::string_view expression) {
    CompileResult compiled = compile_source(expression);
    EXPECT_TRUE(compiled.ok()) << expression << ": " << compiled.error->to_string();
    if (!compiled.ok()) return nullptr;
    return make_tape_field(std::make_shared<const Tape>(std::move(compiled.tape)), {});
}

double max_relative_distance(const Field& field, const Mesh& mesh, const Box& box) {
    auto evaluator = field.make_evaluator();
    double worst = 0.0;
    for (const glm::dvec3& p : mesh.positions) {
        const ValueGradient vg = evaluator->value_gradient(p);
        const double distance =
            vg.value == 0.0 ? 0.0 : std::abs(vg.value) / glm::length(vg.gradient);
        worst = std::max(worst, std::isnan(distance) ? INFINITY : distance);
    }
    return worst / glm::length(box.size());
}

double signed_volume(const Mesh& mesh) {
    double six_volume = 0.0;
    for (const auto& t : mesh.triangles) {
        six_volume +=
            glm::dot(mesh.positions[t[0]], glm::cross(mesh.positions[t[1]], mesh.positions[t[2]]));
    }
    return six_volume / 6.0;
}

namespace {

bool on_box_face(const glm::dvec3& p, const Box& box, int face) {
    const int axis = face / 2;
    return p[axis] == ((face & 1) ? box.hi[axis] : box.lo[axis]);
}

bool on_common_box_face(const glm::dvec3& a, const glm::dvec3& b, const Box& box) {
    for (int face = 0; face < 6; ++face) {
        if (on_box_face(a, box, face) && on_box_face(b, box, face)) return true;
    }
    return false;
}

void expect_consistent_adjacency(const Mesh& mesh, const Box& box, BaseEdges base_edges) {
    ASSERT_EQ(mesh.neighbours.size(), mesh.triangle_count());
    ASSERT_EQ(mesh.base_edge.size(), mesh.triangle_count());
    std::size_t off_box_boundary = 0;
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
        const auto& tri = mesh.triangles[t];
        double longest = 0.0;
        for (int e = 0; e < 3; ++e) {
            longest = std::max(
                longest, glm::distance(mesh.positions[tri[e]], mesh.positions[tri[(e + 1) % 3]]));
        }
        const int b = mesh.base_edge[t];
        ASSERT_LT(b, 3);
        if (base_edges == BaseEdges::longest) {
            EXPECT_EQ(glm::distance(mesh.positions[tri[b]], mesh.positions[tri[(b + 1) % 3]]),
                      longest);
        }
        for (int e = 0; e < 3; ++e) {
            const std::uint32_t n = mesh.neighbours[t][e];
            if (n == kNoNeighbour) {
                off_box_boundary += !on_common_box_face(mesh.positions[tri[e]],
                                                        mesh.positions[tri[(e + 1) % 3]], box);
                continue;
            }
            ASSERT_LT(n, mesh.triangle_count());
            int back = 0;
            for (int f = 0; f < 3; ++f) back += mesh.neighbours[n][f] == t;
            EXPECT_EQ(back, 1) << "triangle " << t << " edge " << e;
        }
    }
    EXPECT_EQ(off_box_boundary, 0u) << "boundary edges off the box's faces";
}

}  // namespace

void expect_valid_mesh(const Field& field, const Mesh& mesh, const Box& box, BaseEdges base_edges) {
    const TopologyReport report = analyze_topology(mesh);
    EXPECT_TRUE(report.manifold()) << report.nonmanifold_edges << " non-manifold edges, "
                                   << report.nonmanifold_vertices << " non-manifold vertices";
    EXPECT_EQ(report.degenerate_triangles, 0u);
    EXPECT_EQ(report.inconsistently_oriented_edges, 0u);
    EXPECT_EQ(report.vertices, mesh.vertex_count()) << "unused vertices";
    ASSERT_EQ(mesh.normals.size(), mesh.vertex_count());
    for (const glm::dvec3& n : mesh.normals) {
        // Unit, or zero where the gradient vanishes (mesh.h).
        if (n != glm::dvec3(0.0)) {
            EXPECT_NEAR(glm::length(n), 1.0, 1e-12);
        }
    }
    EXPECT_LE(max_relative_distance(field, mesh, box), 1e-9);
    expect_consistent_adjacency(mesh, box, base_edges);
    // Outward orientation: each triangle's geometric normal agrees with the gradient normals at
    // its corners. Where the lattice barely cuts a ridge, Marching Cubes can stand a triangle
    // almost across the surface (cosine near 0, either sign), so only clear folds count.
    std::size_t inward = 0;
    for (const auto& t : mesh.triangles) {
        const glm::dvec3 geometric =
            glm::normalize(glm::cross(mesh.positions[t[1]] - mesh.positions[t[0]],
                                      mesh.positions[t[2]] - mesh.positions[t[0]]));
        const glm::dvec3 mean = (mesh.normals[t[0]] + mesh.normals[t[1]] + mesh.normals[t[2]]);
        inward += glm::dot(geometric, mean) < -0.25 * glm::length(mean);
    }
    EXPECT_EQ(inward, 0u) << "triangles facing f < 0";
}

void expect_identical(const Mesh& a, const Mesh& b) {
    ASSERT_EQ(a.positions.size(), b.positions.size());
    ASSERT_EQ(a.triangles.size(), b.triangles.size());
    EXPECT_TRUE(a.positions == b.positions);
    EXPECT_TRUE(a.normals == b.normals);
    EXPECT_TRUE(a.triangles == b.triangles);
    EXPECT_TRUE(a.neighbours == b.neighbours);
    EXPECT_TRUE(a.base_edge == b.base_edge);
}

}  // namespace isomesh::test
