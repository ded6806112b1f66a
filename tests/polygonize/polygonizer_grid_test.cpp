// Sampled grids through the polygonizer: the closed surfaces of the Custodio et al. suite
// (../shared/testdata/mc33, see mc33_suite_test.cpp) seen as grid fields (eval/grid_field.h).
// At and below the grid's own resolution every octree cell holds one trilinear piece, which
// trilinear interpolation of the cell's corners reproduces exactly, so MC33 per cell gives the
// interpolant's topology: components and genus must match the suite's.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <unistd.h>

#include "eval/grid_field.h"
#include "mesh/topology.h"
#include "polygonize/polygonizer.h"
#include "support/mesh_checks.h"
#include "support/shared_data.h"

namespace isomesh {
namespace {

namespace fs = std::filesystem;

/// Unpacks the closed surfaces once into this test's own corner of the build tree. The tests of
/// this file run as concurrent processes: each unpacks into a folder of its own and renames it into
/// place, which is atomic (a later rename fails on the folder already there), so none reads a file
/// another is still writing.
fs::path closed_surfaces() {
    const fs::path dir = fs::path(ISOMESH_BINARY_DIR) / "testdata" / "polygonize";
    const fs::path root = dir / "Closed_Surfaces";
    if (!fs::exists(root)) {
        const fs::path scratch = dir / ("unpacking-" + std::to_string(::getpid()));
        fs::create_directories(scratch);
        const std::string command = "tar -xJf '" ISOMESH_SHARED_DIR
                                    "/testdata/mc33/Closed_Surfaces.tar.xz' -C '" +
                                    scratch.string() + "' --wildcards '*.iso' '*.txt'";
        EXPECT_EQ(std::system(command.c_str()), 0) << command;
        std::error_code lost;  // another process renamed its copy first
        fs::rename(scratch / "Closed_Surfaces", root, lost);
        fs::remove_all(scratch);
    }
    return root;
}

void expect_suite_topology(int first, int step, int min_depth, int max_depth) {
    const fs::path root = closed_surfaces();
    int checked = 0;
    for (int i = first; i < 10000; i += step) {
        std::string error;
        std::optional<IsoGrid> grid =
            load_iso((root / "Grids" / (std::to_string(i) + "-scalar_field.iso")).string(), &error);
        ASSERT_TRUE(grid) << error;
        ASSERT_EQ(grid->nx, 5);
        PolygonizeSettings settings;
        settings.box = grid->box;
        settings.min_depth = min_depth;
        settings.max_depth = max_depth;
        settings.feature_levels = 0;  // a sampled grid has no detail below its cells
        settings.threads = 1;
        const auto field = make_grid_field(std::move(*grid));
        const PolygonizeResult result = polygonize(*field, settings);
        const TopologyReport report = analyze_topology(result.mesh);
        long b0 = -1, genus = -1;
        std::ifstream(root / "InvariantsGrid" / (std::to_string(i) + "-invariant_grid.txt")) >>
            b0 >> genus;
        EXPECT_TRUE(report.watertight()) << "case " << i;
        EXPECT_EQ(report.degenerate_triangles, 0u) << "case " << i;
        EXPECT_EQ(static_cast<long>(report.components), b0) << "case " << i;
        EXPECT_EQ(report.first_betti_number() / 2, genus) << "case " << i;
        EXPECT_GT(test::signed_volume(result.mesh), 0.0) << "case " << i;
        ++checked;
    }
    EXPECT_GT(checked, 0);
}

TEST(PolygonizerGrid, closed_surfaces_at_grid_resolution) {
    ISOMESH_SKIP_WITHOUT_SHARED_DATA();
    expect_suite_topology(0, 10, 2, 2);
}

TEST(PolygonizerGrid, closed_surfaces_below_grid_resolution) {
    ISOMESH_SKIP_WITHOUT_SHARED_DATA();
    expect_suite_topology(3, 10, 2, 3);
}

TEST(PolygonizerGrid, vertices_lie_on_the_interpolant) {
    ISOMESH_SKIP_WITHOUT_SHARED_DATA();
    const fs::path root = closed_surfaces();
    std::string error;
    std::optional<IsoGrid> grid =
        load_iso((root / "Grids" / "78-scalar_field.iso").string(), &error);
    ASSERT_TRUE(grid) << error;
    PolygonizeSettings settings;
    settings.box = grid->box;
    settings.min_depth = 2;
    settings.max_depth = 4;
    settings.feature_levels = 0;
    const auto field = make_grid_field(std::move(*grid));
    const PolygonizeResult result = polygonize(*field, settings);
    ASSERT_GT(result.mesh.triangle_count(), 0u);
    test::expect_valid_mesh(*field, result.mesh, settings.box);
}

}  // namespace
}  // namespace isomesh
