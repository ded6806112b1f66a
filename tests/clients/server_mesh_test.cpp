// `isomesh mesh --server URL` against a real isomesh-server: the same mesh as the in-process run
// of the same request (same vertices and triangles; positions and normals as the protocol carries
// them), and every failure reported with the right exit status.
#include <gtest/gtest.h>

#include <unistd.h>
#include "support/grid_match.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include "client_processes.h"
#include "protocol/mesh_codec.h"
#include "protocol/messages.h"
#include "support/shared_data.h"

namespace isomesh::testing {
namespace {

using Args = std::vector<std::string>;

class MeshOnServer : public ::testing::Test {
  protected:
    static void SetUpTestSuite() { server_ = new ServerProcess(); }
    static void TearDownTestSuite() {
        delete server_;
        server_ = nullptr;
    }
    void SetUp() override { ASSERT_TRUE(server_->ok()) << "isomesh-server:\n" << server_->log(); }

    /// Runs `isomesh mesh ARGS -o FILE` (in-process, or through the server); returns FILE's path.
    std::string run_mesh(Args args, bool on_server, const std::string& file) {
        const std::string path = scratch_ + "/" + file;
        args.insert(args.begin(), "mesh");
        args.insert(args.end(), {"-o", path});
        if (on_server) args.insert(args.end(), {"--server", server_->ws_url()});
        last_run_ = run_program(binary("isomesh"), args);
        EXPECT_EQ(last_run_.status, 0) << last_run_.err;
        return path;
    }
    Mesh mesh(const Args& args, bool on_server) {
        return read_ply(run_mesh(args, on_server, "mesh.ply"));
    }

    static ServerProcess* server_;
    std::string scratch_ = make_scratch();
    ProgramRun last_run_;

  private:
    static std::string make_scratch() {
        static int counter = 0;
        auto path = std::filesystem::temp_directory_path() /
                    ("isomesh_server_mesh_test_" + std::to_string(::getpid()) + "_" +
                     std::to_string(counter++));
        std::filesystem::create_directories(path);
        return path.string();
    }
};

ServerProcess* MeshOnServer::server_ = nullptr;

/// The server's mesh is the in-process one (progressive/pipeline.h on both sides): the same
/// triangles, positions within one step of the session's quantization grid, normals within the
/// 10-bit octahedral coding's error. Vertex order and ids may differ: they depend on how often
/// phase 1 replaced the mesh, which depends on time.
void expect_same_mesh(const Mesh& local, const Mesh& server, const protocol::Box& box) {
    ASSERT_GT(local.triangle_count(), 0u);
    EXPECT_EQ(server.vertex_count(), local.vertex_count());
    EXPECT_EQ(test::compare_on_grid(server, local, protocol::QuantizationGrid::for_box(box), 0.01),
              "");
}

TEST_F(MeshOnServer, refined_mesh_matches_in_process) {
    const Args args = {"x^2+y^2+z^2+2cos(2x)=5", "--box", "-3,3,-3,3,-3,3", "--triangles", "5000"};
    const Mesh local = mesh(args, false);
    const Mesh remote = mesh(args, true);
    EXPECT_EQ(remote.triangle_count(), 5000u);
    expect_same_mesh(local, remote, {-3, 3, -3, 3, -3, 3});
}

TEST_F(MeshOnServer, parameters_and_error_bound_match_in_process) {
    const Args args = {
        "(sqrt(x^2+y^2)-R)^2+z^2=r^2", "--param",     "R=2",  "--param", "r=0.7", "--box",
        "-3.2,3.2,-3.2,3.2,-1.2,1.2",  "--max-error", "0.002"};
    expect_same_mesh(mesh(args, false), mesh(args, true), {-3.2, 3.2, -3.2, 3.2, -1.2, 1.2});
}

TEST_F(MeshOnServer, phase_one_matches_in_process_at_server_depths) {
    // (At the in-process default --depth 4,9 this surface has 1464 triangles, not 328.)
    const Args args = {"x^2+y^2+z^2+2cos(2x)=5", "--box", "-3,3,-3,3,-3,3"};
    Args local_args = args;
    local_args.insert(local_args.end(), {"--depth", "3,9"});
    expect_same_mesh(mesh(local_args, false), mesh(args, true), {-3, 3, -3, 3, -3, 3});
}

TEST_F(MeshOnServer, vm_model_matches_in_process) {
    ISOMESH_SKIP_WITHOUT_SHARED_DATA();
    const Args args = {"@" ISOMESH_SHARED_DIR "/testdata/vm/tanglecube.vm", "--box",
                       "-3,3,-3,3,-3,3", "--triangles", "3000"};
    expect_same_mesh(mesh(args, false), mesh(args, true), {-3, 3, -3, 3, -3, 3});
}

TEST_F(MeshOnServer, writes_glb_and_prints_stats) {
    const std::string path =
        run_mesh({"x^2+y^2+z^2=4", "--box", "-3,3,-3,3,-3,3", "--triangles", "2000", "--stats"},
                 true, "sphere.glb");
    const auto stats = nlohmann::json::parse(last_run_.out);
    EXPECT_EQ(stats["triangles"], 2000);
    EXPECT_GE(stats["frames"].get<int>(), 1);
    EXPECT_GT(stats["bytes_received"].get<int>(), 0);
    std::ifstream glb(path, std::ios::binary);
    char magic[4] = {};
    glb.read(magic, 4);
    EXPECT_EQ(std::string(magic, 4), "glTF");
}

TEST_F(MeshOnServer, server_refusal_is_an_error) {
    const ProgramRun run =
        run_program(binary("isomesh"), {"mesh", "x^2+y^2+z^2=4", "--triangles", "3000000", "-o",
                                        scratch_ + "/big.ply", "--server", server_->ws_url()});
    EXPECT_EQ(run.status, 1);
    EXPECT_NE(run.err.find("budget_too_large"), std::string::npos) << run.err;
    EXPECT_FALSE(std::filesystem::exists(scratch_ + "/big.ply"));
}

TEST(MeshOnServerErrors, unreachable_server_is_an_error) {
    // Nothing listens on port 1 of the loopback address.
    const ProgramRun run = run_program(
        binary("isomesh"),
        {"mesh", "x^2+y^2+z^2=4", "-o", "/tmp/unused.ply", "--server", "ws://127.0.0.1:1/ws"});
    EXPECT_EQ(run.status, 1);
    EXPECT_NE(run.err.find("connect"), std::string::npos) << run.err;
}

TEST(MeshOnServerErrors, usage_mistakes_exit_with_two) {
    const std::vector<Args> mistakes = {
        {"--server", "http://127.0.0.1:8080/ws"},
        {"--server", "ws://127.0.0.1:99999/ws"},
        {"--server", "ws:/oops"},
        {"--server", "ws://127.0.0.1:8080/ws", "--depth", "2,8"},
        {"--server", "ws://127.0.0.1:8080/ws", "--threads", "2"},
    };
    for (const Args& mistake : mistakes) {
        Args args = {"mesh", "x^2+y^2+z^2=4", "-o", "/tmp/unused.ply"};
        args.insert(args.end(), mistake.begin(), mistake.end());
        const ProgramRun run = run_program(binary("isomesh"), args);
        EXPECT_EQ(run.status, 2) << mistake[1] << ": " << run.err;
        EXPECT_NE(run.err.find("--help"), std::string::npos) << run.err;
    }
}

}  // namespace
}  // namespace isomesh::testing
