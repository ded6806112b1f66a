// Sampled grids: the .iso loader (on the Marching Cubes 33 suite's files and on broken files) and
// the trilinear field.
#include "eval/grid_field.h"
#include "support/shared_data.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace isomesh {
namespace {

namespace fs = std::filesystem;

const std::string kArchiveDir = ISOMESH_SHARED_DIR "/testdata/mc33";
const std::string kUnpackDir = ISOMESH_BINARY_DIR "/testdata/mc33";

/// `member` of the mc33 archive `archive`, unpacked into the build tree on first use.
std::string unpacked(const std::string& archive, const std::string& member) {
    std::string path = kUnpackDir + "/" + member;
    if (!fs::exists(path)) {
        fs::create_directories(kUnpackDir);
        std::string command = "tar -xJf '" + kArchiveDir + "/" + archive + "' -C '" + kUnpackDir +
                              "' '" + member + "'";
        EXPECT_EQ(std::system(command.c_str()), 0) << command;
    }
    return path;
}

std::string scratch_file(const std::string& name, const std::vector<unsigned char>& bytes) {
    fs::create_directories(ISOMESH_BINARY_DIR "/testdata/scratch");
    std::string path = ISOMESH_BINARY_DIR "/testdata/scratch/" + name;
    std::ofstream(path, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()),
               static_cast<std::streamsize>(bytes.size()));
    return path;
}

/// The bytes of an .iso file (little endian, as the format says; the test machine is too).
std::vector<unsigned char> iso_bytes(int nx, int ny, int nz, const float box[6],
                                     const std::vector<float>& samples) {
    std::vector<unsigned char> bytes(36 + 4 * samples.size());
    int counts[3] = {nx, ny, nz};
    std::memcpy(bytes.data(), counts, 12);
    std::memcpy(bytes.data() + 12, box, 24);
    if (!samples.empty()) std::memcpy(bytes.data() + 36, samples.data(), 4 * samples.size());
    return bytes;
}

std::string load_error(const std::string& path) {
    std::string error;
    EXPECT_FALSE(load_iso(path, &error).has_value()) << path;
    return error;
}

/// A grid over [0, n-1]^3 (unit cells, so sample positions are exact) of g(i, j, k).
template <class G>
IsoGrid unit_grid(int n, const G& g) {
    IsoGrid grid{n, n, n, {glm::dvec3(0.0), glm::dvec3(n - 1.0)}, {}};
    for (int k = 0; k < n; ++k)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) grid.samples.push_back(static_cast<float>(g(i, j, k)));
    return grid;
}

TEST(LoadIso, reads_marching_cubes_case) {
    ISOMESH_SKIP_WITHOUT_SHARED_DATA();
    std::string error;
    auto grid = load_iso(
        unpacked("MarchingCubes_cases.tar.xz", "MarchingCubes_cases/Grids/7-scalar_field.iso"),
        &error);
    ASSERT_TRUE(grid.has_value()) << error;
    EXPECT_EQ(grid->nx, 2);
    EXPECT_EQ(grid->nz, 2);
    EXPECT_EQ(grid->box.lo, glm::dvec3(0.0));
    EXPECT_EQ(grid->box.hi, glm::dvec3(1.0));
    ASSERT_EQ(grid->samples.size(), 8u);
    EXPECT_FLOAT_EQ(grid->samples[0], 0.296297550201416f);
    EXPECT_FLOAT_EQ(grid->samples[7], 0.8132811188697815f);
    auto e = make_grid_field(*grid)->make_evaluator();
    EXPECT_EQ(e->value({1, 1, 1}), static_cast<double>(grid->samples[7]));
}

TEST(LoadIso, reads_closed_surface_grid) {
    ISOMESH_SKIP_WITHOUT_SHARED_DATA();
    std::string error;
    auto grid = load_iso(
        unpacked("Closed_Surfaces.tar.xz", "Closed_Surfaces/Grids/0-scalar_field.iso"), &error);
    ASSERT_TRUE(grid.has_value()) << error;
    EXPECT_EQ(grid->nx * grid->ny * grid->nz, 125);
    auto field = make_grid_field(*grid);
    EXPECT_EQ(field->domain().lo, grid->box.lo);
    auto e = field->make_evaluator();
    IntervalValue whole = e->interval(grid->box);
    EXPECT_FALSE(whole.maybe_undefined);
    for (float s : grid->samples) EXPECT_TRUE(whole.value.contains(s));
}

TEST(LoadIso, refuses_every_truncation) {
    const float box[6] = {0, 1, 0, 1, 0, 1};
    std::vector<unsigned char> bytes = iso_bytes(2, 2, 2, box, std::vector<float>(8, 1.0f));
    for (std::size_t size = 0; size < bytes.size(); ++size) {
        std::vector<unsigned char> part(bytes.begin(), bytes.begin() + static_cast<long>(size));
        std::string error = load_error(scratch_file("truncated.iso", part));
        EXPECT_NE(error.find("truncated"), std::string::npos) << size << ": " << error;
    }
}

TEST(LoadIso, refuses_trailing_bytes) {
    const float box[6] = {0, 1, 0, 1, 0, 1};
    std::vector<unsigned char> bytes = iso_bytes(2, 2, 2, box, std::vector<float>(9, 1.0f));
    EXPECT_NE(load_error(scratch_file("long.iso", bytes)).find("trailing"), std::string::npos);
}

TEST(LoadIso, refuses_bad_sizes_before_reading_samples) {
    const float box[6] = {0, 1, 0, 1, 0, 1};
    EXPECT_NE(load_error(scratch_file("flat.iso", iso_bytes(1, 2, 2, box, std::vector<float>(4))))
                  .find("nx = 1"),
              std::string::npos);
    EXPECT_NE(
        load_error(scratch_file("negative.iso", iso_bytes(2, -3, 2, box, {}))).find("ny = -3"),
        std::string::npos);
    // A header claiming a billion samples must not allocate them.
    EXPECT_NE(load_error(scratch_file("huge.iso", iso_bytes(60000, 60000, 60000, box, {})))
                  .find("truncated"),
              std::string::npos);
}

TEST(LoadIso, refuses_bad_box_and_samples) {
    const float backwards[6] = {1, 0, 0, 1, 0, 1};
    EXPECT_NE(load_error(scratch_file("backwards.iso",
                                      iso_bytes(2, 2, 2, backwards, std::vector<float>(8))))
                  .find("box"),
              std::string::npos);
    const float box[6] = {0, 1, 0, 1, 0, 1};
    std::vector<float> samples(8, 0.0f);
    samples[3] = std::nanf("");
    EXPECT_NE(
        load_error(scratch_file("nan.iso", iso_bytes(2, 2, 2, box, samples))).find("sample 3"),
        std::string::npos);
}

TEST(LoadIso, refuses_missing_file_and_directory) {
    EXPECT_NE(load_error(ISOMESH_BINARY_DIR "/no/such.iso").find("cannot open"), std::string::npos);
    EXPECT_FALSE(load_iso(ISOMESH_BINARY_DIR, nullptr).has_value());
}

TEST(GridField, interpolates_samples_exactly) {
    IsoGrid grid =
        unit_grid(4, [](int i, int j, int k) { return std::sin(i + 2.0 * j) - 0.1 * k; });
    auto e = make_grid_field(grid)->make_evaluator();
    for (int k = 0; k < 4; ++k)
        for (int j = 0; j < 4; ++j)
            for (int i = 0; i < 4; ++i)
                EXPECT_EQ(e->value({i, j, k}), grid.samples[i + 4 * (j + 4 * k)]);
}

TEST(GridField, interpolates_samples_closely_on_uneven_box) {
    IsoGrid grid{5, 3, 4, {{-1.3, 0.1, 2.0}, {0.7, 0.35, 2.9}}, {}};
    for (int n = 0; n < 60; ++n) grid.samples.push_back(static_cast<float>(std::cos(n)));
    auto e = make_grid_field(grid)->make_evaluator();
    glm::dvec3 step = grid.box.size() / glm::dvec3(4, 2, 3);
    for (int k = 0; k < 4; ++k)
        for (int j = 0; j < 3; ++j)
            for (int i = 0; i < 5; ++i)
                EXPECT_NEAR(e->value(grid.box.lo + glm::dvec3(i, j, k) * step),
                            grid.samples[i + 5 * (j + 3 * k)], 1e-12);
}

TEST(GridField, trilinear_function_is_reproduced_with_its_gradient) {
    auto f = [](double x, double y, double z) {
        return 0.5 * x - 2 * y + 0.25 * z + x * y * z - 1;
    };
    IsoGrid grid = unit_grid(3, f);
    auto e = make_grid_field(grid)->make_evaluator();
    glm::dvec3 p(0.3, 1.7, 1.2);
    EXPECT_NEAR(e->value(p), f(p.x, p.y, p.z), 1e-6);  // samples are floats
    ValueGradient vg = e->value_gradient(p);
    EXPECT_EQ(vg.value, e->value(p));
    EXPECT_NEAR(vg.gradient.x, 0.5 + p.y * p.z, 1e-6);
    EXPECT_NEAR(vg.gradient.y, -2 + p.x * p.z, 1e-6);
    EXPECT_NEAR(vg.gradient.z, 0.25 + p.x * p.y, 1e-6);
}

TEST(GridField, gradient_on_cell_face_comes_from_positive_side) {
    IsoGrid grid = unit_grid(3, [](int i, int, int) { return i == 1 ? 1.0 : 0.0; });  // a tent in x
    auto e = make_grid_field(grid)->make_evaluator();
    EXPECT_EQ(e->value_gradient({1.0, 0.5, 0.5}).gradient.x, -1.0);  // cell [1, 2]
    EXPECT_EQ(e->value_gradient({2.0, 0.5, 0.5}).gradient.x, -1.0);  // the last cell
    EXPECT_EQ(e->value_gradient({0.0, 0.5, 0.5}).gradient.x, 1.0);
}

TEST(GridField, undefined_outside_its_box) {
    IsoGrid grid = unit_grid(3, [](int i, int j, int k) { return i + j + k - 3.0; });
    auto e = make_grid_field(grid)->make_evaluator();
    EXPECT_TRUE(std::isnan(e->value({-0.1, 1, 1})));
    EXPECT_TRUE(std::isnan(e->value_gradient({1, 1, 2.5}).gradient.z));
    IntervalValue leaving = e->interval({{1.5, 1.5, 1.5}, {3, 3, 3}});
    EXPECT_TRUE(leaving.maybe_undefined);
    EXPECT_TRUE(leaving.value.contains(3.0));
    IntervalValue outside = e->interval({{5, 5, 5}, {6, 6, 6}});
    EXPECT_TRUE(outside.value.is_empty() && outside.maybe_undefined);
    IntervalValue inside = e->interval({{0.2, 0.2, 0.2}, {0.8, 0.8, 0.8}});
    EXPECT_FALSE(inside.maybe_undefined);
    EXPECT_LE(inside.value.lo, -3.0);
    EXPECT_GE(inside.value.hi, 0.0);
    EXPECT_LT(inside.value.hi, 0.001);  // one cell: samples -3 .. 0
}

TEST(GridField, interval_gradient_bounds_edge_slopes) {
    IsoGrid grid = unit_grid(4, [](int i, int j, int) { return i * i - 2.0 * j; });
    auto e = make_grid_field(grid)->make_evaluator();
    IntervalGradient g = e->interval_gradient({{0.5, 0.5, 0.5}, {1.5, 1.5, 1.5}});  // cells 0 and 1
    EXPECT_NEAR(g.gradient[0].lo, 1.0, 1e-12);
    EXPECT_NEAR(g.gradient[0].hi, 3.0, 1e-12);
    EXPECT_NEAR(g.gradient[1].lo, -2.0, 1e-12);
    EXPECT_NEAR(g.gradient[1].hi, -2.0, 1e-12);
    EXPECT_NEAR(g.gradient[2].hi, 0.0, 1e-12);
}

TEST(GridField, refuses_invalid_grid) {
    IsoGrid grid{2, 2, 2, {glm::dvec3(0), glm::dvec3(1)}, std::vector<float>(7)};
    EXPECT_THROW(make_grid_field(grid), std::invalid_argument);
    EXPECT_NE(validate_grid(grid).find("7 samples"), std::string::npos);
    grid.samples.resize(8);
    EXPECT_EQ(validate_grid(grid), "");
    grid.box.hi.y = std::numeric_limits<double>::infinity();
    EXPECT_NE(validate_grid(grid).find("along y"), std::string::npos);
}

}  // namespace
}  // namespace isomesh
