// The Custodio et al. Marching Cubes 33 suite ("Practical considerations on Marching Cubes 33
// topological correctness", Computers & Graphics 37(7), 2013), from ../shared/testdata/mc33:
// 10,000 single cells with the Euler characteristic of the trilinear isosurface inside the cell,
// and 10,000 5x5x5 grids of closed surfaces with their Betti numbers.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "mesh/topology.h"
#include "polygonize/mc33.h"
#include "polygonize/uniform_grid_mesher.h"
#include "support/shared_data.h"

namespace isomesh {
namespace {

namespace fs = std::filesystem;

constexpr int kCases = 10000;

fs::path testdata_dir() {
    return fs::path(ISOMESH_BINARY_DIR) / "testdata" / "mc33";
}

/// Unpacks an archive of the shared suite into the build tree once (a marker file records it).
void unpack(const std::string& archive) {
    const fs::path marker = testdata_dir() / (archive + ".unpacked");
    if (fs::exists(marker)) return;
    fs::create_directories(testdata_dir());
    const std::string command = std::string("tar -xJf '" ISOMESH_SHARED_DIR "/testdata/mc33/") +
                                archive + "' -C '" + testdata_dir().string() +
                                "' --wildcards '*.iso' '*.txt'";  // not the .nhdr/.raw copies
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
    std::ofstream(marker) << "ok\n";
}

struct IsoGrid {
    int nx = 0, ny = 0, nz = 0;
    Box box;
    std::vector<double> values;
};

/// The .iso format of ../shared/testdata/README.md: int32 nx, ny, nz; float32 xmin, xmax, ymin,
/// ymax, zmin, zmax; nx * ny * nz float32 samples, x fastest; little endian (as this machine).
IsoGrid read_iso(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::int32_t n[3];
    float bounds[6];
    in.read(reinterpret_cast<char*>(n), sizeof n);
    in.read(reinterpret_cast<char*>(bounds), sizeof bounds);
    IsoGrid grid{n[0],
                 n[1],
                 n[2],
                 Box{{bounds[0], bounds[2], bounds[4]}, {bounds[1], bounds[3], bounds[5]}},
                 {}};
    std::vector<float> samples(static_cast<std::size_t>(n[0]) * n[1] * n[2]);
    in.read(reinterpret_cast<char*>(samples.data()),
            static_cast<std::streamsize>(samples.size() * sizeof(float)));
    EXPECT_TRUE(in.good()) << path;
    grid.values.assign(samples.begin(), samples.end());
    return grid;
}

std::vector<long> read_integers(const fs::path& path) {
    std::ifstream in(path);
    std::vector<long> numbers;
    for (long v; in >> v;) numbers.push_back(v);
    return numbers;
}

/// Euler characteristic of a cell's triangulation, as a surface with boundary.
long euler_characteristic(const CellTriangulation& cell) {
    std::set<int> vertices;
    std::set<std::pair<int, int>> edges;
    for (int t = 0; t < cell.triangle_count; ++t) {
        for (int k = 0; k < 3; ++k) {
            const int a = cell.triangles[t][k], b = cell.triangles[t][(k + 1) % 3];
            vertices.insert(a);
            edges.insert({std::min(a, b), std::max(a, b)});
        }
    }
    return static_cast<long>(vertices.size()) - static_cast<long>(edges.size()) +
           cell.triangle_count;
}

TEST(Mc33Suite, single_cells_have_the_expected_euler_characteristic) {
    ISOMESH_SKIP_WITHOUT_SHARED_DATA();
    unpack("MarchingCubes_cases.tar.xz");
    const fs::path root = testdata_dir() / "MarchingCubes_cases";
    int passed = 0, tubes = 0;
    for (int i = 0; i < kCases; ++i) {
        const IsoGrid grid = read_iso(root / "Grids" / (std::to_string(i) + "-scalar_field.iso"));
        ASSERT_EQ(grid.values.size(), 8u) << "case " << i;
        const std::vector<long> expected =
            read_integers(root / "Grid_invariants" / (std::to_string(i) + "-euler_number.txt"));
        ASSERT_EQ(expected.size(), 1u) << "case " << i;
        std::array<double, 8> corners;
        std::copy(grid.values.begin(), grid.values.end(), corners.begin());
        const CellDecision decision = decide_cell(corners);
        EXPECT_LE(decision.interior_joins, 1) << "case " << i;
        tubes += decision.tube[0] >= 0 ? 1 : 0;
        const long chi = euler_characteristic(triangulate_cell(corners));
        EXPECT_EQ(chi, expected[0]) << "case " << i;
        passed += chi == expected[0] ? 1 : 0;
    }
    EXPECT_EQ(passed, kCases);
    EXPECT_GT(tubes, 0);  // the suite exercises the interior test
    std::cout << "single cells: " << passed << " / " << kCases << " (" << tubes << " tubes)\n";
}

// The invariants are b0 (components) and b1 as the total genus (not 2 x genus, the first Betti
// number of a closed surface): the data has b1 = 1 for single components, which 2 x genus cannot
// be, and a hand count of cases 78 to 81 (one ring through the grid) confirms genus 1.
TEST(Mc33Suite, closed_surfaces_have_the_expected_betti_numbers) {
    ISOMESH_SKIP_WITHOUT_SHARED_DATA();
    unpack("Closed_Surfaces.tar.xz");
    const fs::path root = testdata_dir() / "Closed_Surfaces";
    int passed = 0;
    for (int i = 0; i < kCases; ++i) {
        const IsoGrid grid = read_iso(root / "Grids" / (std::to_string(i) + "-scalar_field.iso"));
        const std::vector<long> expected =
            read_integers(root / "InvariantsGrid" / (std::to_string(i) + "-invariant_grid.txt"));
        ASSERT_EQ(expected.size(), 2u) << "case " << i;
        const Mesh mesh = mesh_sampled_grid({grid.nx, grid.ny, grid.nz, grid.box, grid.values});
        const TopologyReport report = analyze_topology(mesh);
        EXPECT_TRUE(report.watertight() && report.manifold()) << "case " << i;
        EXPECT_EQ(report.inconsistently_oriented_edges, 0u) << "case " << i;
        EXPECT_GT(signed_volume(mesh), 0.0) << "case " << i << ": not facing outwards";
        const long genus = report.first_betti_number() / 2;
        const bool ok = static_cast<long>(report.components) == expected[0] && genus == expected[1];
        EXPECT_TRUE(ok) << "case " << i << ": b0 " << report.components << " genus " << genus
                        << ", expected " << expected[0] << " " << expected[1];
        passed += ok ? 1 : 0;
    }
    EXPECT_EQ(passed, kCases);
    std::cout << "closed surfaces: " << passed << " / " << kCases << "\n";
}

}  // namespace
}  // namespace isomesh
