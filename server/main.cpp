// isomesh-server: the mesh server. `isomesh-server --help` lists the options.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string_view>
#include <vector>

#include <sys/resource.h>

#include "server/config.h"
#include "server/log.h"
#include "server/mesh_service.h"
#include "server/metrics.h"
#include "server/net/http_server.h"
#include "server/resources.h"
#include "server/store/session_store.h"

namespace {

using namespace isomesh::server;

/// The URL a person can open: the bound address, or the loopback one for a wildcard bind.
std::string browser_url(const ServerConfig& config, std::uint16_t port) {
    std::string host = config.bind_address;
    if (host == "0.0.0.0" || host == "::") host = "127.0.0.1";
    if (host.find(':') != std::string::npos) host = "[" + host + "]";
    return "http://" + host + ":" + std::to_string(port) + "/";
}

/// The session store --store names (nullptr for none), or nothing after logging why it cannot
/// be opened. An SQLite file's folder is created when missing.
std::optional<std::unique_ptr<store::SessionStore>> open_session_store(const ServerConfig& config,
                                                                       Logger& logger) {
    const std::string text = resolved_store(config);
    const auto spec = store::parse_store_spec(text);  // checked by parse_config
    if (spec->kind == store::StoreSpec::Kind::sqlite) {
        std::error_code ec;
        const auto folder = std::filesystem::path(spec->path).parent_path();
        if (!folder.empty()) std::filesystem::create_directories(folder, ec);
    }
    // Redis forgets a record nobody touched for the idle timeout and a margin (the server stores
    // activity at most every minute).
    const auto ttl = static_cast<std::uint32_t>(std::min(config.idle_timeout_s + 180.0, 4e9));
    auto opened = store::open_store(*spec, ttl);
    if (!opened) {
        logger.error("store_failed", {{"store", text}, {"message", opened.error().message}});
        std::fprintf(stderr, "isomesh-server: %s\n", opened.error().message.c_str());
        return std::nullopt;
    }
    return std::move(opened).value();
}

void raise_file_limit(Logger& logger);

int serve(const ServerConfig& config) {
    Logger logger(config.log_level);
    raise_file_limit(logger);
    Metrics metrics;
    auto store = open_session_store(config, logger);
    if (!store) return 1;
    MeshService service(config, logger, metrics, std::move(*store));
    net::HttpServer server(service, config, logger, metrics);
    std::uint16_t port = 0;
    try {
        port = server.listen();
    } catch (const std::exception& e) {
        logger.error(
            "listen_failed",
            {{"address", config.bind_address}, {"port", config.port}, {"message", e.what()}});
        return 1;
    }
    // One plain line for the person who started the server; the logs are for machines.
    std::printf("isomesh-server: open %s in a browser (WebSocket at /ws); Ctrl-C stops it\n",
                browser_url(config, port).c_str());
    std::fflush(stdout);
    logger.info("listening", {{"address", config.bind_address},
                              {"port", port},
                              {"url", browser_url(config, port)},
                              {"websocket", "/ws"},
                              {"web_root", config.web_root},
                              {"store", resolved_store(config)},
                              {"worker_threads", resolved_worker_threads(config)}});
    server.run();
    // The drain cancelled every session; a worker that does not check its cancel flag (a long
    // phase 1) must not hold the exit past the drain's deadline.
    const Clock::time_point deadline =
        std::max(server.drain_deadline(), Clock::now() + std::chrono::milliseconds(100));
    if (!service.wait_workers(deadline)) {
        logger.warn("exit_with_busy_workers", {{"busy_workers", metrics.busy_workers.value()}});
        std::fflush(nullptr);
        std::_Exit(0);
    }
    logger.info("stopped");
    return 0;
}

/// Raises the soft limit on open files to the hard one: every connection holds a descriptor.
void raise_file_limit(Logger& logger) {
    rlimit limit{};
    if (getrlimit(RLIMIT_NOFILE, &limit) != 0 || limit.rlim_cur >= limit.rlim_max) return;
    const rlim_t before = limit.rlim_cur;
    limit.rlim_cur = limit.rlim_max;
    if (setrlimit(RLIMIT_NOFILE, &limit) == 0)
        logger.debug("file_limit_raised", {{"from", before}, {"to", limit.rlim_cur}});
}

}  // namespace

int main(int argc, char** argv) {
    configure_allocator();
    ServerConfig defaults;
    defaults.web_root = ISOMESH_DEFAULT_WEB_ROOT;
    defaults.data_dir = default_data_dir([](const char* name) { return std::getenv(name); });
    const std::vector<std::string_view> args(argv + 1, argv + argc);
    const ConfigResult parsed = parse_config(
        args, [](const char* name) { return std::getenv(name); }, defaults);
    if (std::holds_alternative<HelpRequested>(parsed)) {
        std::fputs(config_usage(defaults).c_str(), stdout);
        return 0;
    }
    if (const auto* error = std::get_if<ConfigError>(&parsed)) {
        std::fprintf(stderr, "isomesh-server: %s\nrun 'isomesh-server --help' for usage\n",
                     error->message.c_str());
        return 2;
    }
    try {
        return serve(std::get<ServerConfig>(parsed));
    } catch (const std::exception& e) {
        std::fprintf(stderr, "isomesh-server: internal error: %s\n", e.what());
        return 1;
    }
}
