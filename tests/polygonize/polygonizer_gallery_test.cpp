// The gallery: implicit surfaces whose topology is known, meshed with the default settings (or
// the box and depths noted), checked for exact component count and Euler characteristic, the mesh
// invariants, and identical output for 1, 2 and 3 threads.
#include <atomic>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "eval/tape_field.h"
#include "expr/function_source.h"
#include "mesh/topology.h"
#include "polygonize/polygonizer.h"
#include "support/mesh_checks.h"
#include "support/shared_data.h"

namespace isomesh {
namespace {

struct GalleryCase {
    std::string name;
    std::string expression;
    std::size_t components;
    long euler_characteristic;
    bool closed;  // no boundary: the surface lies inside the box
    Box box{{-5.0, -5.0, -5.0}, {5.0, 5.0, 5.0}};
    int min_depth = 4;
    int max_depth = 9;
};

/// Test output names the case rather than dumping its bytes.
void PrintTo(const GalleryCase& c, std::ostream* os) {
    *os << c.name;
}

Box cube(double lo, double hi) {
    return {{lo, lo, lo}, {hi, hi, hi}};
}

std::vector<GalleryCase> gallery() {
    return {
        {"sphere", "x^2+y^2+z^2=4", 1, 2, true},
        // The thesis's |r| = c, off-centre so that no symmetry of the lattice helps.
        {"thesis_sphere", "sqrt((x-0.3)^2+(y+0.2)^2+(z-0.1)^2)=2.8", 1, 2, true},
        {"ellipsoid", "10x^2+y^2+z^2=20", 1, 2, true},
        {"cosine_sphere", "x^2+y^2+z^2+2cos(2x)=5", 1, 2, true},
        {"torus", "(sqrt(x^2+y^2)-2)^2+z^2=0.64", 1, 0, true},
        // A tube around the figure eight x(x-1)^2(x-2) + y^2 = 0: genus 2.
        {"genus_two",
         "(x(x-1)^2(x-2)+y^2)^2+z^2=0.02",
         1,
         -2,
         true,
         {{-0.5, -1.5, -1.5}, {2.5, 1.5, 1.5}}},
        {"tanglecube", "x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8=0", 1, -8, true},
        // Radius 1, centres 2.02 apart: a gap of 0.02 between them.
        {"touching_spheres", "min((x-1.01)^2+y^2+z^2, (x+1.01)^2+y^2+z^2)=1", 2, 4, true},
        // The same with the gap off the lattice planes: only cells ~0.01 wide separate them.
        {"touching_spheres_off_lattice",
         "min((x-1.133)^2+(y-0.037)^2+(z+0.051)^2, (x+0.887)^2+(y-0.037)^2+(z+0.051)^2)=1", 2, 4,
         true},
        // A big sphere and a tiny one: cells of depth 4 to 9 in one mesh.
        {"big_and_tiny_spheres", "min(x^2+y^2+z^2-9, 400((x-3.6)^2+(y-0.1)^2+(z+0.2)^2)-1)=0", 2, 4,
         true},
        // Found by interval arithmetic although no lattice point at the minimum depth is inside.
        {"tiny_sphere", "(x-0.123)^2+(y+0.234)^2+(z-0.345)^2=0.0025", 1, 2, true},
        // |r| + 2 cos 2x + 2 cos 2y + 2 cos 2z <= 8.67 + 6 < 20 in the default box: nothing.
        {"thesis_bumps_default_box", "sqrt(x^2+y^2+z^2)+2cos(2x)+2cos(2y)+2cos(2z)=20", 0, 0, true},
        // Poles are not surfaces.
        {"pole_plane", "1/x=0", 0, 0, true},
        {"pole_plane_off_lattice", "1/(x-0.37)=0", 0, 0, true},
        {"pole_sphere", "1/(x^2+y^2+z^2-4)=0", 0, 0, true},
        // tan(x) = 0 on [-2, 2]^3: the plane x = 0 (a disk, cut by the box), not the poles at
        // +-pi/2.
        {"tan_plane", "tan(x)=0", 1, 1, false, cube(-2.0, 2.0)},
        {"tan_plane_off_lattice", "tan(x-0.1)=0", 1, 1, false, cube(-2.0, 2.0)},
        // A plane through lattice corners (zero corner values) and tilted.
        {"tilted_plane", "x+2y-0.5z=0.25", 1, 1, false},
        // A tube (one-sheet hyperboloid) through lattice corners such as (1, -1.5, -1.5) next to
        // the box's edges: the vertices of the edges at such a corner meet there, and the
        // zero-length edges between them must collapse (an opposite vertex on the boundary
        // keeping one triangle), or zero-area triangles stay.
        {"hyperboloid_through_corners", "x^2+y^2-z^2=1", 1, 0, false, cube(-2.0, 2.0), 3, 9},
    };
}

class Gallery : public testing::TestWithParam<GalleryCase> {};

TEST_P(Gallery, polygonize_topology_and_invariants) {
    const GalleryCase& c = GetParam();
    const auto field = test::field_of(c.expression);
    ASSERT_TRUE(field);
    PolygonizeSettings settings;
    settings.box = c.box;
    settings.min_depth = c.min_depth;
    settings.max_depth = c.max_depth;
    settings.threads = 1;
    const PolygonizeResult result = polygonize(*field, settings);
    const TopologyReport report = analyze_topology(result.mesh);
    SCOPED_TRACE(c.name + ": " + std::to_string(result.stats.triangles) + " triangles at depth " +
                 std::to_string(result.stats.depth));
    EXPECT_EQ(report.components, c.components);
    EXPECT_EQ(report.euler_characteristic, c.euler_characteristic);
    if (c.closed) {
        EXPECT_TRUE(report.watertight());
        if (c.components > 0) {
            EXPECT_GT(test::signed_volume(result.mesh), 0.0);
        }
    }
    test::expect_valid_mesh(*field, result.mesh, c.box);
    EXPECT_EQ(result.stats.triangles, result.mesh.triangle_count());
    EXPECT_EQ(result.stats.vertices, result.mesh.vertex_count());

    for (int threads : {2, 3}) {
        settings.threads = threads;
        const PolygonizeResult again = polygonize(*field, settings);
        SCOPED_TRACE(std::to_string(threads) + " threads");
        test::expect_identical(result.mesh, again.mesh);
        EXPECT_EQ(again.stats.evaluations, result.stats.evaluations);
    }
}

// The gyroid cut by the default box: no closed form for its topology there, so the count must
// not change with the resolution, and the mesh must be a manifold whose boundary is on the box.
TEST(Polygonizer, gyroid_topology_is_stable_across_resolutions) {
    const auto field = test::field_of("sin(x)cos(y)+sin(y)cos(z)+sin(z)cos(x)=0");
    ASSERT_TRUE(field);
    PolygonizeSettings settings;
    const PolygonizeResult coarse = polygonize(*field, settings);
    settings.min_depth = 5;
    const PolygonizeResult fine = polygonize(*field, settings);
    ASSERT_GT(fine.mesh.triangle_count(), 2 * coarse.mesh.triangle_count());
    const TopologyReport a = analyze_topology(coarse.mesh), b = analyze_topology(fine.mesh);
    EXPECT_EQ(a.components, b.components);
    EXPECT_EQ(a.euler_characteristic, b.euler_characteristic);
    EXPECT_GT(a.boundary_edges, 0u);
    test::expect_valid_mesh(*field, coarse.mesh, settings.box);
    test::expect_valid_mesh(*field, fine.mesh, settings.box);
}

// Adaptivity: the tiny sphere needs cells of depth 9, the big one does not, and the mesh is not
// refined everywhere to the deepest depth.
TEST(Polygonizer, refines_only_where_needed) {
    const auto field = test::field_of("min(x^2+y^2+z^2-9, 400((x-3.6)^2+(y-0.1)^2+(z+0.2)^2)-1)=0");
    ASSERT_TRUE(field);
    const PolygonizeResult result = polygonize(*field, {});
    EXPECT_GE(result.stats.depth, 7);
    EXPECT_LT(result.mesh.triangle_count(), 20000u);
}

TEST(Polygonizer, rejects_invalid_settings) {
    const auto field = test::field_of("x^2+y^2+z^2=1");
    ASSERT_TRUE(field);
    auto expect_rejected = [&](PolygonizeSettings s) {
        EXPECT_THROW(polygonize(*field, s), std::invalid_argument);
    };
    PolygonizeSettings s;
    s.box.hi.y = s.box.lo.y;
    expect_rejected(s);
    s = {};
    s.box.lo.x = NAN;
    expect_rejected(s);
    s = {};
    s.box.hi.z = INFINITY;
    expect_rejected(s);
    s = {};
    s.min_depth = 6;
    s.max_depth = 5;
    expect_rejected(s);
    s = {};
    s.max_depth = 17;
    expect_rejected(s);
    s = {};
    s.min_depth = -1;
    expect_rejected(s);
    s = {};
    s.threads = -2;
    expect_rejected(s);
}

TEST(Polygonizer, cancellation_returns_an_empty_mesh) {
    const auto field = test::field_of("x^2+y^2+z^2=4");
    ASSERT_TRUE(field);
    std::atomic<bool> cancel{true};
    PolygonizeSettings settings;
    settings.cancel = &cancel;
    const PolygonizeResult result = polygonize(*field, settings);
    EXPECT_TRUE(result.stats.cancelled);
    EXPECT_EQ(result.mesh.triangle_count(), 0u);
    cancel = false;
    EXPECT_FALSE(polygonize(*field, settings).stats.cancelled);
}

TEST(Polygonizer, meshes_a_fidget_model) {
    ISOMESH_SKIP_WITHOUT_SHARED_DATA();
    CompileResult compiled = compile_source("@" ISOMESH_SHARED_DIR "/testdata/vm/tanglecube.vm");
    ASSERT_TRUE(compiled.ok());
    const auto field = make_tape_field(std::make_shared<const Tape>(std::move(compiled.tape)), {});
    const PolygonizeResult result = polygonize(*field, {});
    const TopologyReport report = analyze_topology(result.mesh);
    // x^4 - 5x^2 + ... + 10. The critical values of f are c, c - 6.25, c - 12.5, c - 18.75
    // (each of x^4 - 5x^2 has critical values 0 and -6.25): for c = 10 as for c = 11.8 the
    // first two are positive and the last two negative, so the zero set has the same topology
    // as the gallery's tanglecube at 11.8: one surface of genus 5.
    EXPECT_TRUE(report.watertight());
    EXPECT_EQ(report.components, 1u);
    EXPECT_EQ(report.euler_characteristic, -8);
    test::expect_valid_mesh(*field, result.mesh, PolygonizeSettings{}.box);
}

INSTANTIATE_TEST_SUITE_P(Polygonizer, Gallery, testing::ValuesIn(gallery()),
                         [](const testing::TestParamInfo<GalleryCase>& info) {
                             return info.param.name;
                         });

}  // namespace
}  // namespace isomesh
