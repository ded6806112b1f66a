// The server's configuration: command-line flags, each with an environment variable as fallback
// (`--max-sessions-per-connection 8` or ISOMESH_MAX_SESSIONS_PER_CONNECTION=8; a flag wins over
// the environment, the environment over the default). `isomesh-server --help` lists them all.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>

namespace isomesh::server {

enum class LogLevel { debug, info, warn, error };

std::string_view to_string(LogLevel level);
std::optional<LogLevel> log_level_from_string(std::string_view name);

struct ServerConfig {
    // network
    std::string bind_address = "0.0.0.0";
    std::uint16_t port = 8080;  ///< 0: any free port (logged in the "listening" line)
    unsigned io_threads = 1;
    /// The browser client's files, served at GET /. Empty or missing: an embedded page.
    std::string web_root;

    // work
    unsigned worker_threads = 0;  ///< 0: one per core
    /// The workers' scheduling priority, this many nice levels below the network threads'.
    unsigned worker_nice = 5;
    std::uint32_t slice_us = 2000;  ///< refinement time slice per turn of a session
    /// CPU time within which the first mesh of a session (or of a new box) is made.
    std::uint32_t first_mesh_ms = 10;
    std::uint32_t batch_ms = 20;  ///< deltas are flushed at least this often while refining
    std::uint32_t batch_triangles = 2000;  ///< ... and as soon as this many triangles changed
    unsigned draco_speed = 2;  ///< Draco encoder speed: 0 smallest frames ... 10 fastest
    /// New sessions' first meshes kept by request (server/first_mesh_cache.h); 0: none.
    std::size_t first_mesh_cache = 256;
    std::uint64_t first_mesh_cache_mb = 64;  ///< ... and the MiB they may hold

    // access
    /// Origins (scheme://host[:port]) allowed to open a WebSocket, comma-separated; "*": any.
    /// Empty: the server's own origin (the request's Host) and loopback origins only. Requests
    /// without an Origin header (not from a browser) are always allowed.
    std::string allow_origin;

    // limits
    std::size_t max_message_bytes = 1 << 20;  ///< larger control messages get too_large
    /// Sessions one connection may have created and not yet ended (orphaned ones count until
    /// they expire).
    std::size_t max_sessions_per_connection = 16;
    std::size_t max_connections = 1024;  ///< WebSocket connections
    /// Plain HTTP connections (oldest evicted beyond). Every WebSocket is one until its upgrade:
    /// as many as max_connections, or a burst of clients connecting at once to a busy server
    /// loses handshakes (1,000 at once: 42-147 evicted at the former 256).
    std::size_t max_http_connections = 1024;
    std::size_t max_sessions = 1024;  ///< live sessions in total
    /// Memory (MiB) the sessions may reserve and the process may hold before new sessions are
    /// refused (server_busy); 0: half the physical memory.
    std::uint64_t max_memory_mb = 0;
    std::uint64_t session_memory_mb =
        1280;                     ///< one session's memory budget (MiB): 2,000,000 triangles
    double session_cpu_s = 3600;  ///< one session's CPU-time budget over its life
    std::uint64_t max_triangles = 2'000'000;  ///< budgets above this get budget_too_large
    std::uint64_t default_triangles = 20'000;
    double default_max_error = 0.0;  ///< 0: refine to the triangle budget
    /// CPU time (the session's own thread's) for which phase 1 of a version examines cells; a
    /// single step running this long fails the session (eval_timeout).
    std::uint32_t eval_timeout_ms = 10'000;
    std::size_t queue_bytes = 4 << 20;  ///< per-connection output budget (backpressure)
    double idle_timeout_s = 3600;       ///< a session without requests for this long expires
    double orphan_timeout_s = 30;       ///< a session without subscribers for this long expires
    /// SIGTERM, SIGINT, SIGHUP: how long the drain may take before the process exits anyway.
    double drain_timeout_s = 5;

    // sessions kept across restarts (server/store/session_store.h)
    /// "none", "sqlite:PATH" or "redis://HOST:PORT"; empty: sqlite:DATA_DIR/sessions.db
    std::string store;
    std::string data_dir = "isomesh-data";  ///< the server's files (main() sets the default)

    LogLevel log_level = LogLevel::info;
};

/// What parse_config found: a configuration, a request for help, or a usage error (message).
struct HelpRequested {};
struct ConfigError {
    std::string message;
};
using ConfigResult = std::variant<ServerConfig, HelpRequested, ConfigError>;

/// Reads `args` (without the program name) as `--name value` or `--name=value`, with `getenv`
/// consulted for every option not given on the command line, over `defaults`. Never throws on bad
/// input.
ConfigResult parse_config(std::span<const std::string_view> args,
                          const std::function<const char*(const char*)>& getenv,
                          const ServerConfig& defaults = {});

/// The --help text: every option, its environment variable and its default.
std::string config_usage(const ServerConfig& defaults = {});

/// The worker thread count: config.worker_threads, or the number of cores when 0.
unsigned resolved_worker_threads(const ServerConfig& config);

/// The --store value in force: config.store, or the SQLite file in the data directory.
std::string resolved_store(const ServerConfig& config);

/// The default data directory: $XDG_STATE_HOME/isomesh, else $HOME/.local/state/isomesh, else
/// ./isomesh-data.
std::string default_data_dir(const std::function<const char*(const char*)>& getenv);

/// The memory limit in bytes: config.max_memory_mb, or half the physical memory when 0.
std::uint64_t resolved_max_memory_bytes(const ServerConfig& config);

}  // namespace isomesh::server
