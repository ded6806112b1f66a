#include "server/config.h"

#include <gtest/gtest.h>

#include <map>
#include <string>
#include <vector>

namespace isomesh::server {
namespace {

ConfigResult parse(std::vector<std::string_view> args,
                   std::map<std::string, std::string> env = {}) {
    return parse_config(args, [&env](const char* name) -> const char* {
        auto it = env.find(name);
        return it == env.end() ? nullptr : it->second.c_str();
    });
}

ServerConfig parsed(std::vector<std::string_view> args,
                    std::map<std::string, std::string> env = {}) {
    ConfigResult result = parse(std::move(args), std::move(env));
    if (auto* error = std::get_if<ConfigError>(&result)) ADD_FAILURE() << error->message;
    EXPECT_TRUE(std::holds_alternative<ServerConfig>(result));
    return std::holds_alternative<ServerConfig>(result) ? std::get<ServerConfig>(result)
                                                        : ServerConfig{};
}

std::string error_of(std::vector<std::string_view> args,
                     std::map<std::string, std::string> env = {}) {
    ConfigResult result = parse(std::move(args), std::move(env));
    auto* error = std::get_if<ConfigError>(&result);
    return error ? error->message : "(no error)";
}

TEST(ParseConfig, defaults_without_arguments) {
    const ServerConfig c = parsed({});
    EXPECT_EQ(c.port, 8080);
    EXPECT_EQ(c.bind_address, "0.0.0.0");
    EXPECT_EQ(c.worker_threads, 0u);
    EXPECT_EQ(c.log_level, LogLevel::info);
}

TEST(ParseConfig, flags_in_both_forms) {
    const ServerConfig c = parsed({"--port", "0", "--threads=3", "--log-level", "debug",
                                   "--web-root", "/srv/web", "--orphan-timeout", "0.5"});
    EXPECT_EQ(c.port, 0);
    EXPECT_EQ(c.worker_threads, 3u);
    EXPECT_EQ(c.log_level, LogLevel::debug);
    EXPECT_EQ(c.web_root, "/srv/web");
    EXPECT_DOUBLE_EQ(c.orphan_timeout_s, 0.5);
}

TEST(ParseConfig, environment_fills_in_and_flags_win) {
    const ServerConfig c = parsed({"--port", "9000"}, {{"ISOMESH_PORT", "7000"},
                                                       {"ISOMESH_MAX_SESSIONS_PER_CONNECTION", "3"},
                                                       {"ISOMESH_LOG_LEVEL", "warn"}});
    EXPECT_EQ(c.port, 9000);
    EXPECT_EQ(c.max_sessions_per_connection, 3u);
    EXPECT_EQ(c.log_level, LogLevel::warn);
}

TEST(ParseConfig, rejects_bad_values_naming_the_source) {
    EXPECT_NE(error_of({"--port", "70000"}).find("--port"), std::string::npos);
    EXPECT_NE(error_of({"--port", "12ab"}).find("between 0 and 65535"), std::string::npos);
    EXPECT_NE(error_of({}, {{"ISOMESH_THREADS", "-1"}}).find("ISOMESH_THREADS"), std::string::npos);
    EXPECT_NE(error_of({"--idle-timeout", "nan"}).find("--idle-timeout"), std::string::npos);
    EXPECT_NE(error_of({"--log-level", "loud"}).find("debug, info"), std::string::npos);
}

TEST(ParseConfig, rejects_unknown_repeated_and_incomplete_options) {
    EXPECT_NE(error_of({"--colour", "red"}).find("unknown option"), std::string::npos);
    EXPECT_NE(error_of({"--port", "1", "--port", "2"}).find("twice"), std::string::npos);
    EXPECT_NE(error_of({"--port"}).find("needs a value"), std::string::npos);
    EXPECT_NE(error_of({"8080"}).find("unexpected argument"), std::string::npos);
    EXPECT_NE(error_of({"--default-triangles", "10", "--max-triangles", "5"}).find("exceeds"),
              std::string::npos);
}

TEST(ParseConfig, help_is_requested_and_lists_every_variable) {
    EXPECT_TRUE(std::holds_alternative<HelpRequested>(parse({"--port", "1", "--help"})));
    const std::string usage = config_usage();
    for (const char* name : {"--port", "ISOMESH_PORT", "--queue-bytes", "ISOMESH_QUEUE_BYTES",
                             "--eval-timeout-ms", "--first-mesh-ms", "--first-mesh-cache",
                             "ISOMESH_FIRST_MESH_CACHE_MB", "ISOMESH_LOG_LEVEL"})
        EXPECT_NE(usage.find(name), std::string::npos) << name;
}

TEST(ParseConfig, budgets_and_access_options) {
    const ServerConfig c =
        parsed({"--max-sessions", "8", "--max-memory-mb", "512", "--session-memory-mb", "64",
                "--session-cpu-s", "2.5", "--max-http-connections", "32", "--allow-origin",
                "https://app.example, http://localhost:5173"});
    EXPECT_EQ(c.max_sessions, 8u);
    EXPECT_EQ(resolved_max_memory_bytes(c), std::uint64_t{512} << 20);
    EXPECT_EQ(c.session_memory_mb, 64u);
    EXPECT_DOUBLE_EQ(c.session_cpu_s, 2.5);
    EXPECT_EQ(c.max_http_connections, 32u);
    EXPECT_EQ(c.allow_origin, "https://app.example, http://localhost:5173");
    EXPECT_EQ(parsed({"--first-mesh-cache", "0"}).first_mesh_cache, 0u);  // none kept
    EXPECT_EQ(parsed({"--first-mesh-cache-mb", "8"}).first_mesh_cache_mb, 8u);
    EXPECT_EQ(parsed({}).worker_nice, 5u);  // the network threads come first
    EXPECT_EQ(parsed({"--worker-nice", "0"}).worker_nice, 0u);
    EXPECT_NE(error_of({"--worker-nice", "20"}).find("--worker-nice"), std::string::npos);
    EXPECT_GT(resolved_max_memory_bytes(parsed({})), 0u);  // 0: half the physical memory
    EXPECT_NE(error_of({"--allow-origin", "app.example"}).find("--allow-origin"),
              std::string::npos);
    EXPECT_NE(error_of({"--max-sessions", "0"}).find("--max-sessions"), std::string::npos);
}

TEST(ParseConfig, help_documents_the_signals_and_every_budget) {
    const std::string usage = config_usage();
    for (const char* text : {"SIGHUP", "does not reload", "503", "1001", "--max-sessions",
                             "--max-memory-mb", "--session-memory-mb", "--session-cpu-s",
                             "--max-http-connections", "--allow-origin", "CPU time"})
        EXPECT_NE(usage.find(text), std::string::npos) << text;
}

TEST(ParseConfig, given_defaults_are_the_base) {
    ServerConfig defaults;
    defaults.web_root = "/opt/web";
    auto result = parse_config(
        {}, [](const char*) -> const char* { return nullptr; }, defaults);
    ASSERT_TRUE(std::holds_alternative<ServerConfig>(result));
    EXPECT_EQ(std::get<ServerConfig>(result).web_root, "/opt/web");
}

}  // namespace
}  // namespace isomesh::server
