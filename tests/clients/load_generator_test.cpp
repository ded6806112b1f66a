// isomesh-load: its parts (mix files, percentiles, /metrics text, URLs), and a short real run
// against isomesh-server.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "client_processes.h"
#include "load_mix.h"
#include "load_run.h"
#include "load_stats.h"
#include "ws_client.h"

namespace isomesh::load {
namespace {

using testing::binary;
using testing::ProgramRun;
using testing::run_program;
using testing::ServerProcess;

TEST(LoadMix, default_mix_is_the_gallery_with_sliders) {
    const Mix mix = default_mix();
    ASSERT_GE(mix.size(), 4u);
    EXPECT_EQ(mix[0].create.source.text, "x^2+y^2+z^2+2cos(2x)=5");
    const auto sliders = std::count_if(mix.begin(), mix.end(),
                                       [](const MixEntry& e) { return e.slider.has_value(); });
    EXPECT_GT(sliders, 0);
    EXPECT_LT(sliders, static_cast<long>(mix.size()));
    for (const MixEntry& entry : mix) {
        if (entry.slider) {
            EXPECT_TRUE(entry.create.parameters.contains(entry.slider->parameter));
        }
    }
}

TEST(LoadMix, reads_weights_sliders_and_create_fields) {
    const Mix mix = parse_mix(R"([
      {"name": "s", "expression": "x^2+y^2+z^2=a", "parameters": {"a": 4}, "weight": 3,
       "box": [-3, 3, -3, 3, -3, 3], "constraints": {"triangles": 500},
       "slider": {"parameter": "a", "min": 2, "max": 6}},
      {"vm": "_0 var-x\n", "box": [-1, 1, -1, 1, -1, 1]}])");
    ASSERT_EQ(mix.size(), 2u);
    EXPECT_EQ(mix[0].name, "s");
    EXPECT_EQ(mix[0].weight, 3u);
    EXPECT_EQ(mix[0].create.constraints.triangles, 500u);
    ASSERT_TRUE(mix[0].slider);
    EXPECT_EQ(mix[0].slider->max, 6);
    EXPECT_EQ(mix[1].name, "entry 2");
    EXPECT_EQ(mix[1].create.source.kind, protocol::Source::Kind::vm);
}

TEST(LoadMix, rejects_bad_entries_naming_them) {
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"[", "not valid JSON"},
        {"[]", "non-empty"},
        {R"([{"expression": "x", "box": [1, -1, 0, 1, 0, 1]}])", "entry 1"},
        {R"([{"box": [0, 1, 0, 1, 0, 1]}])", "entry 1"},
        {R"([{"expression": "x", "box": [0, 1, 0, 1, 0, 1], "weight": 0}])", "weight"},
        {R"([{"expression": "x", "box": [0, 1, 0, 1, 0, 1]},
             {"expression": "x=a", "box": [0, 1, 0, 1, 0, 1],
              "slider": {"parameter": "a", "min": 0, "max": 1}}])",
         "entry 2: the slider's parameter 'a' needs a starting value"},
        {R"([{"expression": "x=a", "parameters": {"a": 1}, "box": [0, 1, 0, 1, 0, 1],
              "slider": {"parameter": "a", "min": 1, "max": 0}}])",
         "min must be below max"},
        {R"([{"expression": "x", "box": [0, 1, 0, 1, 0, 1], "typo": 1}])", "typo"},
    };
    for (const auto& [text, expected] : cases) {
        try {
            parse_mix(text);
            ADD_FAILURE() << "accepted: " << text;
        } catch (const std::runtime_error& error) {
            EXPECT_NE(std::string(error.what()).find(expected), std::string::npos) << error.what();
        }
    }
}

TEST(LoadMix, users_and_rounds_walk_the_weighted_entries) {
    const Mix mix = parse_mix(R"([{"name": "a", "expression": "x", "box": [0,1,0,1,0,1]},
                                  {"name": "b", "expression": "x", "box": [0,1,0,1,0,1],
                                   "weight": 2}])");
    std::string seen;
    for (std::size_t user = 0; user < 3; ++user) seen += mix_entry(mix, user, 3, 0).name;
    EXPECT_EQ(seen, "abb");
    EXPECT_EQ(mix_entry(mix, 0, 2, 1).name, "b");  // slot 2: user 0's second session
    EXPECT_EQ(mix_entry(mix, 1, 2, 1).name, "a");  // slot 3 = 0 modulo 3
}

TEST(LoadMix, jittered_moves_parameters_and_grows_the_box_reproducibly) {
    const Mix mix = parse_mix(R"([{"expression": "x^2+y^2+z^2=a", "parameters": {"a": 4},
                                   "box": [-3, 3, -3, 3, -3, 3]}])");
    const MixEntry a = jittered(mix[0], 0.01, 7);
    EXPECT_EQ(a.create, jittered(mix[0], 0.01, 7).create);  // the same seed, the same session
    EXPECT_NE(a.create, jittered(mix[0], 0.01, 8).create);
    EXPECT_NE(a.create.parameters.at("a"), 4.0);
    EXPECT_NEAR(a.create.parameters.at("a"), 4.0, 0.04);
    for (int axis = 0; axis < 3; ++axis) {
        EXPECT_LE(a.create.box[2 * axis], -3.0);  // grown: the surface stays inside
        EXPECT_GE(a.create.box[2 * axis], -3.06);
        EXPECT_GE(a.create.box[2 * axis + 1], 3.0);
        EXPECT_LE(a.create.box[2 * axis + 1], 3.06);
    }
}

TEST(Percentiles, nearest_rank_picks_measured_samples) {
    std::vector<double> samples;
    for (int i = 100; i >= 1; --i) samples.push_back(i);
    const Percentiles p = percentiles(samples);
    EXPECT_EQ(p.count, 100u);
    EXPECT_EQ(p.p50, 50);
    EXPECT_EQ(p.p90, 90);
    EXPECT_EQ(p.p99, 99);
    EXPECT_EQ(p.max, 100);
    const Percentiles one = percentiles({7.5});
    EXPECT_EQ(one.p50, 7.5);
    EXPECT_EQ(one.p99, 7.5);
    EXPECT_EQ(percentiles({}).count, 0u);
}

TEST(Metrics, parses_prometheus_samples) {
    const MetricSamples samples = parse_metrics(
        "# HELP isomesh_sessions Live sessions.\n# TYPE isomesh_sessions gauge\n"
        "isomesh_sessions 3\nisomesh_errors_total{code=\"bad json\"} 2\n"
        "isomesh_latency_bucket{le=\"+Inf\"} 7\nbroken line\nisomesh_x 1e-3\n");
    ASSERT_EQ(samples.size(), 4u);
    EXPECT_EQ(samples.at("isomesh_sessions"), 3);
    EXPECT_EQ(samples.at("isomesh_errors_total{code=\"bad json\"}"), 2);
    EXPECT_EQ(samples.at("isomesh_latency_bucket{le=\"+Inf\"}"), 7);
    EXPECT_DOUBLE_EQ(samples.at("isomesh_x"), 1e-3);
}

TEST(Url, reads_ws_and_http_urls) {
    const net::Url url = net::parse_url("ws://127.0.0.1:8080/ws");
    EXPECT_EQ(url.scheme, "ws");
    EXPECT_EQ(url.host, "127.0.0.1");
    EXPECT_EQ(url.port, "8080");
    EXPECT_EQ(url.target, "/ws");
    EXPECT_EQ(url.with("http", "/metrics").to_string(), "http://127.0.0.1:8080/metrics");
    const net::Url v6 = net::parse_url("http://[::1]");
    EXPECT_EQ(v6.host, "::1");
    EXPECT_EQ(v6.port, "80");
    EXPECT_EQ(v6.target, "/");
    EXPECT_EQ(v6.to_string(), "http://[::1]:80/");
    for (const char* bad :
         {"127.0.0.1:8080", "wss://h/ws", "ws://:80/", "ws://h:0/", "ws://h:65536/", "ws://h:8a/",
          "ws://u@h/", "ws://[::1/", "ws://h/#x"}) {
        EXPECT_THROW(net::parse_url(bad), net::NetError) << bad;
    }
}

class LoadRun : public ::testing::Test {
  protected:
    std::string json_path_ = (std::filesystem::temp_directory_path() /
                              ("isomesh_load_test_" + std::to_string(::getpid()) + ".json"))
                                 .string();
    void TearDown() override { std::filesystem::remove(json_path_); }

    nlohmann::json report(const ProgramRun& run) {
        std::ifstream file(json_path_);
        auto json = nlohmann::json::parse(file, nullptr, false);
        EXPECT_FALSE(json.is_discarded()) << run.out << run.err;
        return json;
    }
};

TEST_F(LoadRun, three_sessions_decode_frames_without_errors) {
    ServerProcess server;
    ASSERT_TRUE(server.ok()) << server.log();
    for (const char* version : {"1", "2"}) {
        SCOPED_TRACE(std::string("protocol version ") + version);
        const ProgramRun run = run_program(
            binary("isomesh-load"), {"--url", server.ws_url(), "--sessions", "3", "--duration", "2",
                                     "--protocol-version", version, "--json", json_path_});
        EXPECT_EQ(run.status, 0) << run.out << run.err;
        const nlohmann::json r = report(run);
        EXPECT_EQ(r["errors"]["total"], 0) << r["errors"].dump();
        EXPECT_GT(r["frames"]["decoded"].get<int>(), 3);
        EXPECT_GE(r["time_to_first_mesh_ms"]["count"].get<int>(), 3);
        EXPECT_GT(r["time_to_first_mesh_ms"]["p50"].get<double>(), 0.0);
        // Its parts: every session's `created`, and its first keyframe's delivery.
        EXPECT_GE(r["create_to_created_ms"]["count"].get<int>(),
                  r["time_to_first_mesh_ms"]["count"].get<int>());
        EXPECT_EQ(r["first_mesh_delivery_ms"]["count"], r["time_to_first_mesh_ms"]["count"]);
        EXPECT_LE(r["create_to_created_ms"]["p50"].get<double>(),
                  r["time_to_first_mesh_ms"]["max"].get<double>());
        EXPECT_EQ(r["frame_latency_ms"]["count"], r["frames"]["decoded"]);
        EXPECT_GT(r["triangles_per_s"].get<double>(), 0.0);
        EXPECT_GT(r["updates_sent"].get<int>(), 0);  // session 2 of the mix has a slider
        const auto& metrics = r["server_metrics"];
        ASSERT_TRUE(metrics["after"].is_object()) << metrics.dump();
        EXPECT_GE(metrics["after"]["isomesh_sessions_created_total"].get<double>() -
                      metrics["before"]["isomesh_sessions_created_total"].get<double>(),
                  3.0);
        EXPECT_EQ(r["resyncs"], 0) << "every delta fitted the replica";
        // The table names the figures for people.
        EXPECT_NE(run.out.find("time to first mesh"), std::string::npos) << run.out;
    }
}

TEST_F(LoadRun, unreachable_server_fails_the_run) {
    const ProgramRun run = run_program(
        binary("isomesh-load"), {"--url", "ws://127.0.0.1:1/ws", "--sessions", "2", "--duration",
                                 "0.5", "--ramp", "0", "--json", json_path_});
    EXPECT_EQ(run.status, 1) << run.out << run.err;
    const nlohmann::json r = report(run);
    EXPECT_EQ(r["errors"]["connection"], 2);
    EXPECT_EQ(r["frames"]["decoded"], 0);
    EXPECT_TRUE(r["server_metrics"]["before"].is_null());
}

TEST(LoadCommandLine, mistakes_exit_with_two) {
    for (const std::vector<std::string>& args : std::vector<std::vector<std::string>>{
             {},
             {"--url", "http://127.0.0.1:1/ws"},
             {"--url", "ws://127.0.0.1:1/ws", "--sessions", "0"},
             {"--url", "ws://127.0.0.1:1/ws", "--duration", "-1"},
             {"--url", "ws://127.0.0.1:1/ws", "--bogus", "1"},
             {"--url", "ws://127.0.0.1:1/ws", "--protocol-version", "3"},
         }) {
        const ProgramRun run = run_program(binary("isomesh-load"), args);
        EXPECT_EQ(run.status, 2) << run.err;
    }
    const ProgramRun bad_mix = run_program(
        binary("isomesh-load"), {"--url", "ws://127.0.0.1:1/ws", "--mix", "/nonexistent.json"});
    EXPECT_EQ(bad_mix.status, 1);
    EXPECT_NE(bad_mix.err.find("/nonexistent.json"), std::string::npos) << bad_mix.err;
}

}  // namespace
}  // namespace isomesh::load
