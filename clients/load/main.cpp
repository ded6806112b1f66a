// isomesh-load: a load generator for isomesh-server. Opens N sessions over WebSocket, decodes
// every frame with the protocol library, and reports latencies, throughput and errors as a table
// (stdout) and as JSON (--json FILE, or stdout with --json -).
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "args.h"
#include "load_report.h"
#include "load_run.h"

namespace {

using isomesh::cli::Arguments;
using isomesh::cli::OptionSpec;
using isomesh::cli::parse_number;
using isomesh::cli::UsageError;
using namespace isomesh::load;

constexpr std::string_view kUsage =
    R"(usage: isomesh-load --url ws://HOST:PORT/ws [--sessions N] [--duration S] [--mix FILE]
                    [--updates-per-s R] [--hold S] [--ramp S] [--threads T]
                    [--protocol-version V] [--jitter J] [--json FILE]

Opens N sessions on an isomesh server, one WebSocket connection each, for S seconds: a mix of
surfaces (the viewer's gallery by default), some moving a parameter like a slider. Decodes every
frame, then reports time to first mesh, frame latency (the frames' server timestamps against this
machine's clock: run it on the server's machine), update-to-frame latency, triangles and bytes per
second, errors, and the server's /metrics before and after. Exits 1 if anything failed.
  --url URL           the server's WebSocket (loopback or a test host only)
  --sessions N        concurrent sessions (default 10, at most 10000)
  --duration S        seconds before every session is closed (default 10, at most 3600)
  --mix FILE          a JSON array of create requests (see clients/load/load_mix.h)
  --updates-per-s R   updates per second of each slider session (default 2, 0 = still)
  --hold S            a static session is closed S seconds after converging and the next surface
                      of the mix created (default 2; 0 = keep it to the end)
  --ramp S            sessions start evenly spread over S seconds (default 1)
  --threads T         I/O threads, which also decode the frames (default 2)
  --protocol-version V  the protocol version the sessions speak: 2 (default: deltas carry only
                      what the client lacks, PROTOCOL.md 4.5) or 1
  --jitter J          moves each session's parameters and box at random by up to J times their
                      values (0 to 0.5; default 0): sessions of one mix entry then ask for
                      meshes of their own, as distinct users would, instead of the same one
                      (which a server may answer from its first-mesh cache)
  --json FILE         also write the report as JSON to FILE ('-': stdout, instead of the table)
)";

constexpr OptionSpec kOptions[] = {
    {"url", true, false},           {"sessions", true, false},
    {"duration", true, false},      {"mix", true, false},
    {"updates-per-s", true, false}, {"hold", true, false},
    {"ramp", true, false},          {"threads", true, false},
    {"json", true, false},          {"protocol-version", true, false},
    {"jitter", true, false}};

double option_number(const Arguments& args, std::string_view name, double fallback, double lo,
                     double hi, bool whole) {
    const auto text = args.value(name);
    if (!text) return fallback;
    const std::string what = "--" + std::string(name);
    const double value = parse_number(*text, what);
    if (value < lo || value > hi ||
        (whole && value != static_cast<double>(static_cast<long long>(value)))) {
        throw UsageError(what + ": expected " + (whole ? "a whole number" : "a number") + " from " +
                         std::to_string(lo) + " to " + std::to_string(hi));
    }
    return value;
}

LoadOptions parse_options(const Arguments& args) {
    if (!args.positional().empty()) throw UsageError("unexpected argument");
    if (!args.has("url")) throw UsageError("missing --url ws://HOST:PORT/ws");
    LoadOptions options;
    try {
        options.url = isomesh::net::parse_url(*args.value("url"));
    } catch (const isomesh::net::NetError& error) {
        throw UsageError(std::string("--url: ") + error.what());
    }
    if (options.url.scheme != "ws") throw UsageError("--url: expected a ws:// URL");
    options.sessions =
        static_cast<std::size_t>(option_number(args, "sessions", 10, 1, 10000, true));
    options.duration_s = option_number(args, "duration", 10, 0.1, 3600, false);
    options.ramp_s = option_number(args, "ramp", 1, 0, 3600, false);
    options.threads = static_cast<unsigned>(option_number(args, "threads", 2, 1, 64, true));
    options.user.updates_per_s = option_number(args, "updates-per-s", 2, 0, 1000, false);
    options.user.hold_s = option_number(args, "hold", 2, 0, 3600, false);
    options.user.jitter = option_number(args, "jitter", 0, 0, 0.5, false);
    options.user.protocol_version = static_cast<int>(
        option_number(args, "protocol-version", isomesh::protocol::kMaxProtocolVersion, 1,
                      isomesh::protocol::kMaxProtocolVersion, true));
    options.mix = args.has("mix") ? load_mix_file(std::string(*args.value("mix"))) : default_mix();
    return options;
}

void write_json(const nlohmann::ordered_json& json, const std::string& path) {
    const std::string text = json.dump(2) + "\n";
    if (path == "-") {
        std::fputs(text.c_str(), stdout);
        return;
    }
    std::ofstream out(path);
    out << text;
    out.close();
    if (!out) throw std::runtime_error("cannot write " + path);
}

int run(std::span<const std::string_view> raw) {
    Arguments args(raw, kOptions);
    if (args.help()) {
        std::fputs(kUsage.data(), stdout);
        return 0;
    }
    const LoadOptions options = parse_options(args);
    const LoadReport report = run_load(options);
    const auto json_path = args.value("json");
    if (json_path) write_json(report_json(report), std::string(*json_path));
    if (!json_path || *json_path != "-") std::fputs(report_table(report).c_str(), stdout);
    const bool failed = report.stats.error_count() > 0 || report.stats.frames == 0;
    if (report.stats.frames == 0) std::fputs("isomesh-load: no frame decoded\n", stderr);
    return failed ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) {
    const std::vector<std::string_view> args(argv + 1, argv + argc);
    try {
        return run(args);
    } catch (const UsageError& error) {
        std::fprintf(stderr, "isomesh-load: %s\nrun 'isomesh-load --help' for usage\n",
                     error.what());
        return 2;
    } catch (const std::exception& error) {
        std::fprintf(stderr, "isomesh-load: %s\n", error.what());
        return 1;
    }
}
