// `isomesh mesh` end to end (phase 1 only): the files it writes and its --stats line.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

namespace {

namespace fs = std::filesystem;

struct MeshRun {
    int status = -1;
    std::string out;  // stdout; stderr goes to the test's own
};

/// Runs build/bin/isomesh with `arguments` (already quoted for the shell).
MeshRun run_isomesh(const std::string& arguments) {
    const std::string command = std::string("'") + std::string(ISOMESH_BINARY_DIR) +
                                std::string("/bin/isomesh' mesh ") + arguments;
    MeshRun run;
    FILE* pipe = popen(command.c_str(), "r");
    if (pipe == nullptr) return run;
    char buffer[4096];
    for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0;)
        run.out.append(buffer, n);
    const int raw = pclose(pipe);
    run.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
    return run;
}

fs::path scratch(const std::string& name) {
    return fs::temp_directory_path() /
           (std::string("isomesh_mesh_test_") + std::to_string(::getpid()) + name);
}

std::string read_file(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

TEST(MeshCommand, writes_a_binary_ply_with_normals_and_prints_stats) {
    const fs::path ply = scratch(".ply");
    const MeshRun run =
        run_isomesh(std::string("'x^2+y^2+z^2=4' -o '") + ply.string() + "' --stats --threads 2");
    ASSERT_EQ(run.status, 0);
    const nlohmann::json stats = nlohmann::json::parse(run.out);
    for (const char* key : {"triangles", "vertices", "evaluations", "time_ms"}) {
        EXPECT_TRUE(stats.contains(key)) << key;
    }
    const std::size_t triangles = stats["triangles"], vertices = stats["vertices"];
    EXPECT_GT(triangles, 100u);

    const std::string data = read_file(ply);
    const std::string end = "end_header\n";
    const std::size_t body = data.find(end);
    ASSERT_NE(body, std::string::npos);
    const std::string header = data.substr(0, body);
    EXPECT_NE(header.find("format binary_little_endian 1.0"), std::string::npos);
    EXPECT_NE(header.find(std::string("element vertex ") + std::to_string(vertices)),
              std::string::npos);
    EXPECT_NE(header.find("property float nz"), std::string::npos);
    EXPECT_NE(header.find(std::string("element face ") + std::to_string(triangles)),
              std::string::npos);
    // Six floats per vertex, then a count byte and three int32 per face.
    EXPECT_EQ(data.size() - body - end.size(), vertices * 24 + triangles * 13);
    float first[3];
    std::memcpy(first, data.data() + body + end.size(), sizeof first);
    EXPECT_NEAR(std::sqrt(first[0] * first[0] + first[1] * first[1] + first[2] * first[2]), 2.0,
                1e-6);
    fs::remove(ply);
}

TEST(MeshCommand, writes_obj_with_parameters_and_box) {
    const fs::path obj = scratch(".obj");
    const MeshRun run = run_isomesh(
        std::string("'x^2+y^2+z^2=r^2' --param r=1.5 --box -2,2,-2,2,-2,2 --depth 3,6 -o '") +
        obj.string() + "'");
    ASSERT_EQ(run.status, 0);
    std::ifstream in(obj);
    std::size_t v = 0, vn = 0, f = 0;
    for (std::string line; std::getline(in, line);) {
        v += line.starts_with("v ");
        vn += line.starts_with("vn ");
        f += line.starts_with("f ");
    }
    EXPECT_GT(f, 0u);
    EXPECT_EQ(v, vn);
    fs::remove(obj);
}

TEST(MeshCommand, meshes_a_sampled_grid) {
    // A 3 x 3 x 3 grid over [0, 1]^3, negative only at the centre: a small closed blob.
    const fs::path iso = scratch(".iso"), ply = scratch("_grid.ply");
    {
        std::ofstream out(iso, std::ios::binary);
        const std::int32_t n[3] = {3, 3, 3};
        const float bounds[6] = {0, 1, 0, 1, 0, 1};
        out.write(reinterpret_cast<const char*>(n), sizeof n);
        out.write(reinterpret_cast<const char*>(bounds), sizeof bounds);
        for (int i = 0; i < 27; ++i) {
            const float value = i == 13 ? -1.0f : 1.0f;
            out.write(reinterpret_cast<const char*>(&value), sizeof value);
        }
    }
    const MeshRun run = run_isomesh(std::string("'@") + iso.string() + std::string("' -o '") +
                                    ply.string() + "' --stats");
    ASSERT_EQ(run.status, 0);
    const nlohmann::json stats = nlohmann::json::parse(run.out);
    EXPECT_EQ(stats["depth"], 1);      // the grid's own cells
    EXPECT_EQ(stats["triangles"], 8);  // one corner cut in each of the 8 cells
    fs::remove(iso);
    fs::remove(ply);
}

TEST(MeshCommand, refuses_bad_input_with_an_error_status) {
    const std::string out = std::string("-o '") + scratch(".ply").string() + "'";
    EXPECT_EQ(run_isomesh(std::string("'x^2+' ") + out + " 2>/dev/null").status, 1);  // syntax
    EXPECT_EQ(run_isomesh("'x^2=1' -o /tmp/x.xyz 2>/dev/null").status, 2);            // file type
    EXPECT_EQ(run_isomesh("'x^2=1' 2>/dev/null").status, 2);                          // no -o
    EXPECT_EQ(run_isomesh(std::string("'x=1' --depth 5,4 ") + out + " 2>/dev/null").status, 2);
    EXPECT_EQ(run_isomesh(std::string("'x=1' --depth 1,17 ") + out + " 2>/dev/null").status, 2);
    EXPECT_EQ(run_isomesh(std::string("'x=1' --box 1,0,0,1,0,1 ") + out + " 2>/dev/null").status,
              2);
    EXPECT_EQ(run_isomesh(std::string("'x=1' --threads -1 ") + out + " 2>/dev/null").status, 2);
    EXPECT_EQ(run_isomesh(std::string("'a x=1' ") + out + " 2>/dev/null").status,
              1);  // no value for a
    EXPECT_EQ(run_isomesh(std::string("@/nonexistent.iso ") + out + " 2>/dev/null").status, 1);
    EXPECT_EQ(run_isomesh("'x=1' -o /nonexistent/dir/x.ply 2>/dev/null").status, 1);
}

}  // namespace
