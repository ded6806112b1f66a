// The gallery: implicit surfaces whose topology is known, meshed with the default settings (or
// the box and depths noted), checked for exact component count and Euler characteristic, the mesh
// invariants, and identical output for 1, 2 and 3 threads.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "mesh/topology.h"
#include "polygonize/polygonizer.h"
#include "polygonize_support.h"

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

INSTANTIATE_TEST_SUITE_P(Polygonizer, Gallery, testing::ValuesIn(gallery()),
                         [](const testing::TestParamInfo<GalleryCase>& info) {
                             return info.param.name;
                         });

}  // namespace
}  // namespace isomesh
