// Refinement of the polygonizer's gallery (tests/polygonize/polygonizer_gallery_test.cpp): the
// mesh stays conforming, watertight where the surface is closed, and of the same topology after
// every step of splits and then of merges; every vertex lies on the surface; the deltas replay.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "fixtures.h"
#include "mesh/topology.h"
#include "polygonize/polygonizer.h"
#include "refine/refiner.h"

namespace isomesh {
namespace {

struct GalleryCase {
    std::string name;
    std::string expression;
    bool closed;
    Box box{{-5.0, -5.0, -5.0}, {5.0, 5.0, 5.0}};
};

/// Test output names the case rather than dumping its bytes.
void PrintTo(const GalleryCase& c, std::ostream* os) {
    *os << c.name;
}

std::vector<GalleryCase> gallery() {
    const Box small{{-2.0, -2.0, -2.0}, {2.0, 2.0, 2.0}};
    return {
        {"sphere", "x^2+y^2+z^2=4", true},
        {"thesis_sphere", "sqrt((x-0.3)^2+(y+0.2)^2+(z-0.1)^2)=2.8", true},
        {"ellipsoid", "10x^2+y^2+z^2=20", true},
        {"cosine_sphere", "x^2+y^2+z^2+2cos(2x)=5", true},
        {"torus", "(sqrt(x^2+y^2)-2)^2+z^2=0.64", true},
        {"genus_two",
         "(x(x-1)^2(x-2)+y^2)^2+z^2=0.02",
         true,
         {{-0.5, -1.5, -1.5}, {2.5, 1.5, 1.5}}},
        {"tanglecube", "x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8=0", true},
        {"touching_spheres", "min((x-1.01)^2+y^2+z^2, (x+1.01)^2+y^2+z^2)=1", true},
        {"tiny_sphere", "(x-0.123)^2+(y+0.234)^2+(z-0.345)^2=0.0025", true},
        {"tan_plane", "tan(x)=0", false, small},
        {"tan_plane_off_lattice", "tan(x-0.1)=0", false, small},
        {"tilted_plane", "x+2y-0.5z=0.25", false},
        {"gyroid", "sin(x)cos(y)+sin(y)cos(z)+sin(z)cos(x)=0", false},
        // Two blobs of 32 phase-1 triangles each: the vertex normals at a base edge's ends differ
        // by up to 130 degrees, and the midpoint projected along their mean folds the children;
        // along the diamond's face normals it does not (every split was refused before).
        {"two_small_blobs", "(x^2-0.8)^2+y^2+z^2=0.3", true, small},
        // Through lattice corners next to the box's edges, its boundary on two faces there.
        {"hyperboloid_through_corners", "x^2+y^2-z^2=1", false, small},
    };
}

Mesh phase1(const Field& field, const Box& box, int threads) {
    PolygonizeSettings settings;
    settings.box = box;
    settings.min_depth = 3;
    settings.threads = threads;
    return polygonize(field, settings).mesh;
}

class RefineGallery : public testing::TestWithParam<GalleryCase> {};

TEST_P(RefineGallery, conforming_after_every_step_of_splits_and_merges) {
    const GalleryCase& c = GetParam();
    const auto field = test::compile_field(c.expression);
    const Mesh first = phase1(*field, c.box, 1);
    ASSERT_GT(first.triangles.size(), 0u);
    // Refinement keeps whatever phase 1 gives: the same boundary loops (none for a closed
    // surface, unless phase 1 left holes: that is phase 1's test to catch), no new degenerate
    // triangles, the same topology.
    const TopologyReport start = analyze_topology(first);
    const std::size_t loops = test::boundary_loops(first);
    if (c.closed && loops != 0)
        std::printf("note: phase 1 left %zu holes in %s (tests/polygonize checks that)\n", loops,
                    c.name.c_str());
    const test::Boundary boundary = loops == 0 ? test::Boundary::None
                                    : c.closed ? test::Boundary::Anywhere
                                               : test::Boundary::OnBoxFaces;
    const std::size_t budget = first.triangles.size() + 3000;
    RefineSettings settings;
    settings.constraint = Constraint::triangle_budget(budget);
    Refiner refiner(field, first, settings);
    const MeshDelta snapshot = refiner.snapshot();
    std::vector<MeshDelta> deltas;

    auto check_steps = [&](std::size_t operations) {
        for (int step = 0; step < 1000; ++step) {
            StepResult r = refiner.step({operations});
            deltas.push_back(std::move(r.delta));
            const Mesh mesh = refiner.mesh().mesh;
            ASSERT_EQ(test::check_conforming(mesh, boundary), "") << "step " << step;
            ASSERT_EQ(test::boundary_loops(mesh), loops) << "step " << step;
            const TopologyReport now = analyze_topology(mesh);
            ASSERT_EQ(now.components, start.components) << "step " << step;
            ASSERT_EQ(now.euler_characteristic, start.euler_characteristic) << "step " << step;
            ASSERT_LE(now.degenerate_triangles, start.degenerate_triangles) << "step " << step;
            if (r.converged) return;
        }
        FAIL() << "no convergence";
    };
    check_steps(400);
    EXPECT_GE(refiner.stats().triangles + 1, budget);
    EXPECT_LE(refiner.stats().triangles, budget);
    refiner.set_constraint(Constraint::triangle_budget(first.triangles.size() + 500));
    check_steps(400);
    EXPECT_GT(refiner.counters().merges, 0u);

    // Every vertex on the surface, to the projection tolerance (relative to the local edge).
    const RefinedMesh m = refiner.mesh();
    auto e = field->make_evaluator();
    const double box_size = glm::length(c.box.size());
    std::size_t off = 0;
    for (const glm::dvec3& p : m.mesh.positions) {
        const ValueGradient vg = e->value_gradient(p);
        if (!(std::abs(vg.value) / glm::length(vg.gradient) < 1e-9 * box_size)) ++off;
    }
    // A split whose vertex cannot be placed there is not made (refiner.h: refused_vertices).
    EXPECT_EQ(off, 0u);

    std::string error;
    EXPECT_TRUE(test::same_mesh(test::replay_mesh(snapshot, deltas, &error), test::canonical(m)));
    EXPECT_EQ(error, "");
}

INSTANTIATE_TEST_SUITE_P(Gallery, RefineGallery, testing::ValuesIn(gallery()),
                         [](const testing::TestParamInfo<GalleryCase>& info) {
                             return info.param.name;
                         });

// Phase 1 gives the same mesh for any thread count, and refinement is single-threaded and
// deterministic: the refined mesh does not depend on the thread count either.
TEST(RefineGallery, same_result_for_any_thread_count) {
    const auto field = test::compile_field("x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8=0");
    std::vector<RefinedMesh> results;
    for (int threads : {1, 2, 3}) {
        RefineSettings settings;
        settings.constraint = Constraint::triangle_budget(8000);
        Refiner refiner(field, phase1(*field, {{-5, -5, -5}, {5, 5, 5}}, threads), settings);
        refiner.run_to_convergence();
        results.push_back(refiner.mesh());
    }
    for (std::size_t i = 1; i < results.size(); ++i) {
        EXPECT_TRUE(test::same_mesh(results[0].mesh, results[i].mesh));
        EXPECT_EQ(results[0].triangle_ids, results[i].triangle_ids);
    }
}

}  // namespace
}  // namespace isomesh
