#include "server/config.h"

#include "server/handshake.h"
#include "server/store/session_store.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <limits>
#include <thread>

#include <unistd.h>

namespace isomesh::server {
namespace {

constexpr std::array<std::string_view, 4> kLogLevelNames = {"debug", "info", "warn", "error"};

/// The error message of a rejected value, or nothing when it was stored.
using Setter = std::function<std::optional<std::string>(ServerConfig&, std::string_view)>;
using Shower = std::function<std::string(const ServerConfig&)>;

struct Option {
    std::string_view name;  // without "--"
    std::string_view help;
    Setter set;
    Shower show;
};

std::optional<std::uint64_t> parse_integer(std::string_view text) {
    std::uint64_t value = 0;
    const char* end = text.data() + text.size();
    auto [ptr, ec] = std::from_chars(text.data(), end, value);
    if (text.empty() || ec != std::errc() || ptr != end) return std::nullopt;
    return value;
}

std::optional<double> parse_real(std::string_view text) {
    double value = 0;
    const char* end = text.data() + text.size();
    auto [ptr, ec] = std::from_chars(text.data(), end, value);
    if (text.empty() || ec != std::errc() || ptr != end || !std::isfinite(value))
        return std::nullopt;
    return value;
}

std::string range_message(std::string_view what, auto low, auto high) {
    return std::string(what) + " between " + std::to_string(low) + " and " + std::to_string(high);
}

/// An option holding an integer field in [low, high].
template <class T>
Option integer_option(std::string_view name, std::string_view help, T ServerConfig::*field,
                      std::uint64_t low, std::uint64_t high) {
    Setter set = [=](ServerConfig& c, std::string_view text) -> std::optional<std::string> {
        auto value = parse_integer(text);
        if (!value || *value < low || *value > high) return range_message("an integer", low, high);
        c.*field = static_cast<T>(*value);
        return std::nullopt;
    };
    Shower show = [=](const ServerConfig& c) { return std::to_string(c.*field); };
    return {name, help, set, show};
}

Option real_option(std::string_view name, std::string_view help, double ServerConfig::*field,
                   double low, double high) {
    Setter set = [=](ServerConfig& c, std::string_view text) -> std::optional<std::string> {
        auto value = parse_real(text);
        if (!value || *value < low || *value > high) return range_message("a number", low, high);
        c.*field = *value;
        return std::nullopt;
    };
    Shower show = [=](const ServerConfig& c) {
        std::string text = std::to_string(c.*field);
        text.erase(text.find_last_not_of('0') + 1);
        if (text.back() == '.') text.pop_back();
        return text;
    };
    return {name, help, set, show};
}

Option string_option(std::string_view name, std::string_view help,
                     std::string ServerConfig::*field) {
    Setter set = [=](ServerConfig& c, std::string_view text) -> std::optional<std::string> {
        c.*field = std::string(text);
        return std::nullopt;
    };
    Shower show = [=](const ServerConfig& c) { return c.*field; };
    return {name, help, set, show};
}

Option store_option() {
    Setter set = [](ServerConfig& c, std::string_view text) -> std::optional<std::string> {
        if (!text.empty() && !store::parse_store_spec(text))
            return "none, sqlite:PATH or redis://HOST:PORT";
        c.store = std::string(text);
        return std::nullopt;
    };
    Shower show = [](const ServerConfig& c) { return resolved_store(c); };
    return {"store",
            "where sessions are kept across restarts: sqlite:PATH (one server), "
            "redis://HOST:PORT (shared by several servers) or none (in memory only)",
            set, show};
}

Option log_level_option() {
    Setter set = [](ServerConfig& c, std::string_view text) -> std::optional<std::string> {
        auto level = log_level_from_string(text);
        if (!level) return "one of debug, info, warn, error";
        c.log_level = *level;
        return std::nullopt;
    };
    Shower show = [](const ServerConfig& c) { return std::string(to_string(c.log_level)); };
    return {"log-level", "debug, info, warn or error", set, show};
}

Option allow_origin_option() {
    Setter set = [](ServerConfig& c, std::string_view text) -> std::optional<std::string> {
        if (auto problem = check_allow_origin(text)) return "a list of origins: " + *problem;
        c.allow_origin = std::string(text);
        return std::nullopt;
    };
    Shower show = [](const ServerConfig& c) { return c.allow_origin; };
    return {"allow-origin",
            "origins allowed to open a WebSocket, comma-separated, e.g. "
            "'https://example.org,http://localhost:5173'; '*': any (empty: this server's own "
            "origin and loopback origins; clients that send no Origin, i.e. not browsers, are "
            "always allowed)",
            set, show};
}

const std::vector<Option>& options() {
    constexpr std::uint64_t kU32 = std::numeric_limits<std::uint32_t>::max();
    constexpr double kDay = 86400;
    static const std::vector<Option> table = {
        string_option("bind", "address to listen on", &ServerConfig::bind_address),
        integer_option("port", "TCP port (0: any free port)", &ServerConfig::port, 0, 65535),
        integer_option("io-threads", "network threads", &ServerConfig::io_threads, 1, 64),
        string_option("web-root", "folder of the browser client served at / (empty: built-in page)",
                      &ServerConfig::web_root),
        integer_option("threads",
                       "refinement worker threads (0: one per core); idle ones help the "
                       "running sessions' phase 1",
                       &ServerConfig::worker_threads, 0, 256),
        integer_option("worker-nice",
                       "nice levels the refinement workers run below the network threads: with "
                       "every core busy, accepting connections, reading requests and writing "
                       "frames come first (0: the same priority)",
                       &ServerConfig::worker_nice, 0, 19),
        integer_option("slice-us", "refinement time slice per turn of a session, microseconds",
                       &ServerConfig::slice_us, 100, 1'000'000),
        integer_option(
            "first-mesh-ms",
            "CPU time within which the first mesh of a session (or of a new box) is made, "
            "whatever the function; later keyframes improve it",
            &ServerConfig::first_mesh_ms, 1, 60'000),
        integer_option("batch-ms", "longest wait before refinement deltas are sent",
                       &ServerConfig::batch_ms, 1, 10'000),
        integer_option("batch-triangles", "triangles changed that trigger sending a delta",
                       &ServerConfig::batch_triangles, 1, kU32),
        integer_option("draco-speed", "Draco encoder speed, 0 (smallest frames) to 10 (fastest)",
                       &ServerConfig::draco_speed, 0, 10),
        integer_option("first-mesh-cache",
                       "first meshes of new sessions kept by request (function, parameters, "
                       "box, constraints; a request is kept when asked for a second time), least "
                       "recently used dropped first: sessions opening the same example share "
                       "their first mesh's work (0: none kept)",
                       &ServerConfig::first_mesh_cache, 0, 1 << 20),
        integer_option("first-mesh-cache-mb", "MiB the first meshes kept may hold",
                       &ServerConfig::first_mesh_cache_mb, 1, 1ull << 20),
        integer_option("max-message-bytes", "largest control message accepted",
                       &ServerConfig::max_message_bytes, 256, 64 << 20),
        allow_origin_option(),
        integer_option("max-sessions-per-connection",
                       "sessions one connection may have created and not yet ended (orphaned "
                       "ones count until they expire)",
                       &ServerConfig::max_sessions_per_connection, 1, 1 << 20),
        integer_option("max-connections", "simultaneous WebSocket connections",
                       &ServerConfig::max_connections, 1, 1 << 20),
        integer_option("max-http-connections",
                       "simultaneous plain HTTP connections (beyond: the oldest is closed)",
                       &ServerConfig::max_http_connections, 1, 1 << 20),
        integer_option("max-sessions", "live sessions in total (beyond: server_busy)",
                       &ServerConfig::max_sessions, 1, 1 << 20),
        integer_option("max-memory-mb",
                       "MiB the sessions may reserve (triangle budget times the bytes a "
                       "triangle costs) and the process may hold before new sessions get "
                       "server_busy (0: half the physical memory)",
                       &ServerConfig::max_memory_mb, 0, 1ull << 30),
        integer_option("session-memory-mb",
                       "MiB one session may hold (a larger triangle budget gets "
                       "budget_too_large; a session growing beyond ends with resource_limit)",
                       &ServerConfig::session_memory_mb, 1, 1ull << 30),
        real_option("session-cpu-s",
                    "CPU seconds one session may use over its life (beyond: resource_limit)",
                    &ServerConfig::session_cpu_s, 0.001, 365 * kDay),
        integer_option("max-triangles", "largest triangle budget a session may ask for",
                       &ServerConfig::max_triangles, 1, 1ull << 40),
        integer_option("default-triangles", "triangle budget of a session that names none",
                       &ServerConfig::default_triangles, 1, 1ull << 40),
        real_option("default-max-error", "error bound of a session that names none (0: none)",
                    &ServerConfig::default_max_error, 0, 1e300),
        integer_option("eval-timeout-ms",
                       "CPU time (of the session's own work and of the workers helping it, not "
                       "wall clock) for which phase 1 of "
                       "a function version examines cells before keeping the mesh it has; a "
                       "single step running this long ends the session with eval_timeout",
                       &ServerConfig::eval_timeout_ms, 1, kU32),
        integer_option("queue-bytes",
                       "output bytes queued per connection before deltas are dropped",
                       &ServerConfig::queue_bytes, 4096, 1ull << 34),
        real_option("idle-timeout", "seconds without requests after which a session expires",
                    &ServerConfig::idle_timeout_s, 0.01, 365 * kDay),
        real_option("orphan-timeout", "seconds without subscribers after which a session expires",
                    &ServerConfig::orphan_timeout_s, 0, 365 * kDay),
        real_option("drain-timeout",
                    "seconds the drain may take (SIGTERM, SIGINT, SIGHUP): sessions are "
                    "cancelled and closed at once, queued frames leave, then the process exits "
                    "even if a worker is still busy",
                    &ServerConfig::drain_timeout_s, 0, 3600),
        store_option(),
        string_option("data-dir", "folder of the server's files (the default session store)",
                      &ServerConfig::data_dir),
        log_level_option(),
    };
    return table;
}

/// ISOMESH_ followed by the option's name in upper case with '_' for '-'.
std::string env_name(std::string_view option) {
    std::string name = "ISOMESH_";
    for (char c : option) name += c == '-' ? '_' : static_cast<char>(std::toupper(c));
    return name;
}

const Option* find_option(std::string_view name) {
    for (const Option& option : options()) {
        if (option.name == name) return &option;
    }
    return nullptr;
}

std::optional<std::string> apply(ServerConfig& config, const Option& option, std::string_view value,
                                 std::string_view source) {
    if (auto problem = option.set(config, value))
        return std::string(source) + ": expected " + *problem + ", got '" + std::string(value) +
               "'";
    return std::nullopt;
}

}  // namespace

std::string_view to_string(LogLevel level) {
    return kLogLevelNames[static_cast<int>(level)];
}

std::optional<LogLevel> log_level_from_string(std::string_view name) {
    auto it = std::find(kLogLevelNames.begin(), kLogLevelNames.end(), name);
    if (it == kLogLevelNames.end()) return std::nullopt;
    return static_cast<LogLevel>(it - kLogLevelNames.begin());
}

ConfigResult parse_config(std::span<const std::string_view> args,
                          const std::function<const char*(const char*)>& getenv,
                          const ServerConfig& defaults) {
    ServerConfig config = defaults;
    for (const Option& option : options()) {
        const std::string variable = env_name(option.name);
        if (const char* value = getenv(variable.c_str())) {
            if (auto error = apply(config, option, value, variable)) return ConfigError{*error};
        }
    }
    std::vector<std::string_view> given;
    for (std::size_t i = 0; i < args.size(); ++i) {
        std::string_view arg = args[i];
        if (arg == "--help" || arg == "-h") return HelpRequested{};
        if (!arg.starts_with("--"))
            return ConfigError{"unexpected argument '" + std::string(arg) + "'"};
        arg.remove_prefix(2);
        std::optional<std::string_view> value;
        if (auto eq = arg.find('='); eq != std::string_view::npos) {
            value = arg.substr(eq + 1);
            arg = arg.substr(0, eq);
        }
        const Option* option = find_option(arg);
        if (!option) return ConfigError{"unknown option '--" + std::string(arg) + "'"};
        if (std::find(given.begin(), given.end(), arg) != given.end())
            return ConfigError{"option '--" + std::string(arg) + "' given twice"};
        given.push_back(arg);
        if (!value) {
            if (i + 1 == args.size())
                return ConfigError{"option '--" + std::string(arg) + "' needs a value"};
            value = args[++i];
        }
        if (auto error = apply(config, *option, *value, "--" + std::string(arg)))
            return ConfigError{*error};
    }
    if (config.default_triangles > config.max_triangles)
        return ConfigError{"--default-triangles exceeds --max-triangles"};
    return config;
}

std::string config_usage(const ServerConfig& defaults) {
    std::string text =
        "usage: isomesh-server [--OPTION VALUE]...\n\n"
        "Serves isosurface meshing sessions over WebSocket at /ws, the browser client at /,\n"
        "/healthz, /readyz and /metrics (Prometheus). Every option may also be set by the "
        "environment\n"
        "variable shown; the command line wins.\n\n"
        "Signals: SIGTERM, SIGINT and SIGHUP drain the server (SIGHUP does not reload): it stops\n"
        "taking new WebSocket connections and sessions, /healthz and /readyz answer 503\n"
        "\"draining\", every session ends here with `closed` (reason shutdown, or moved when the\n"
        "store keeps it), connections close with code 1001 once their queued frames have left,\n"
        "and the process exits 0 within --drain-timeout (plus about a second), whatever its\n"
        "workers are doing.\n\noptions:\n";
    for (const Option& option : options()) {
        text += "  --" + std::string(option.name) + " (" + env_name(option.name) + ", default '" +
                option.show(defaults) + "')\n      " + std::string(option.help) + "\n";
    }
    return text;
}

std::string resolved_store(const ServerConfig& config) {
    if (!config.store.empty()) return config.store;
    return "sqlite:" + config.data_dir + "/sessions.db";
}

std::string default_data_dir(const std::function<const char*(const char*)>& getenv) {
    const char* state = getenv("XDG_STATE_HOME");
    if (state && *state) return std::string(state) + "/isomesh";
    const char* home = getenv("HOME");
    if (home && *home) return std::string(home) + "/.local/state/isomesh";
    return "isomesh-data";
}

std::uint64_t resolved_max_memory_bytes(const ServerConfig& config) {
    if (config.max_memory_mb > 0) return config.max_memory_mb << 20;
    const long pages = sysconf(_SC_PHYS_PAGES);
    const long page_size = sysconf(_SC_PAGE_SIZE);
    if (pages <= 0 || page_size <= 0) return std::uint64_t{4} << 30;
    return static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page_size) / 2;
}

unsigned resolved_worker_threads(const ServerConfig& config) {
    if (config.worker_threads > 0) return config.worker_threads;
    return std::max(1u, std::thread::hardware_concurrency());
}

}  // namespace isomesh::server
