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
                             "--eval-timeout-ms", "ISOMESH_LOG_LEVEL"})
        EXPECT_NE(usage.find(name), std::string::npos) << name;
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
