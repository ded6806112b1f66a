// A lone session on a real isomesh-server with two workers: the idle worker helps its phase 1
// (/metrics' help counter rises; a one-worker server's stays at 0), and the final mesh is the one
// the one-worker server makes (the same triangles on the same quantized positions).
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "client_processes.h"
#include "load_run.h"
#include "support/shared_data.h"
#include "ws_client.h"

namespace isomesh::testing {
namespace {

using Triangle = std::array<std::array<float, 3>, 3>;

/// The mesh's triangles as position triples, each rotated to start at its least position (the
/// orientation kept), sorted: vertex and triangle ids depend on timing, this does not.
std::vector<Triangle> canonical(const Mesh& mesh) {
    std::vector<Triangle> out;
    out.reserve(mesh.triangles.size());
    for (const auto& t : mesh.triangles) {
        Triangle p;
        for (int k = 0; k < 3; ++k) {
            const auto& v = mesh.positions[t[k]];
            p[k] = {static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)};
        }
        std::rotate(p.begin(), std::min_element(p.begin(), p.end()), p.end());
        out.push_back(p);
    }
    std::sort(out.begin(), out.end());
    return out;
}

double help_items(const ServerProcess& server) {
    const net::Url url = net::parse_url(server.ws_url()).with("http", "/metrics");
    const load::MetricSamples samples = load::parse_metrics(net::http_get(url));
    const auto it = samples.find("isomesh_help_items_total");
    return it == samples.end() ? -1.0 : it->second;
}

std::vector<Triangle> mesh_on(const ServerProcess& server, const std::string& name) {
    const std::string path = (std::filesystem::temp_directory_path() /
                              ("isomesh_server_help_" + std::to_string(::getpid()) + name))
                                 .string();
    const ProgramRun run =
        run_program(binary("isomesh"), {"mesh", "@" ISOMESH_SHARED_DIR "/testdata/vm/bear.vm",
                                        "--box", "-1,1,-1,1,-1,1", "--triangles", "20000", "-o",
                                        path, "--server", server.ws_url()});
    EXPECT_EQ(run.status, 0) << run.err;
    const std::vector<Triangle> triangles = canonical(read_ply(path));
    std::filesystem::remove(path);
    return triangles;
}

TEST(ServerHelp, lone_session_is_helped_by_the_idle_worker_and_meshes_as_with_one_worker) {
    ISOMESH_SKIP_WITHOUT_SHARED_DATA();
    // Phase 1 runs to its end on both (on a loaded machine bear.vm's took more than the default
    // 10 s of CPU time, then kept the mesh it had at that time).
    const ServerProcess two({"--threads", "2", "--eval-timeout-ms", "600000"});
    const ServerProcess one({"--threads", "1", "--eval-timeout-ms", "600000"});
    ASSERT_TRUE(two.ok()) << two.log();
    ASSERT_TRUE(one.ok()) << one.log();
    EXPECT_EQ(help_items(two), 0.0);
    const std::vector<Triangle> helped = mesh_on(two, "two.ply");
    const std::vector<Triangle> alone = mesh_on(one, "one.ply");
    ASSERT_GT(alone.size(), 0u);
    EXPECT_TRUE(helped == alone) << helped.size() << " triangles helped, " << alone.size()
                                 << " alone";
    EXPECT_GT(help_items(two), 0.0);  // bear.vm's phase 1 spans many loops: the idle one helped
    EXPECT_EQ(help_items(one), 0.0);  // no other worker
}

}  // namespace
}  // namespace isomesh::testing
