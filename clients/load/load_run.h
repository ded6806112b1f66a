// A load run: N virtual users against one server for a fixed time, then one report.
#pragma once

#include <map>
#include <optional>
#include <string>

#include "load_mix.h"
#include "load_stats.h"
#include "virtual_user.h"
#include "ws_client.h"

namespace isomesh::load {

struct LoadOptions {
    net::Url url;               ///< the server's WebSocket, ws://HOST:PORT/ws
    std::size_t sessions = 10;  ///< virtual users, each with one session at a time
    double duration_s = 10;     ///< from the first connection to the stop
    double ramp_s = 1;          ///< users start evenly spread over this time
    unsigned threads = 2;       ///< I/O threads (frames are decoded on them)
    UserSettings user;
    Mix mix;
};

/// Prometheus text format samples by series (`name{labels}`), comments dropped.
using MetricSamples = std::map<std::string, double>;

/// Parses the sample lines of a /metrics page; lines it cannot read are skipped.
MetricSamples parse_metrics(std::string_view text);

struct LoadReport {
    LoadOptions options;
    double elapsed_s = 0;        ///< from the first connection to the last one ending
    std::size_t unfinished = 0;  ///< users whose connection had not ended by the grace time
    LoadStats stats;
    std::optional<MetricSamples> metrics_before;  ///< the server's /metrics; nothing if it failed
    std::optional<MetricSamples> metrics_after;
    std::string metrics_error;  ///< why a /metrics read failed
};

/// Runs the load and gathers the report. Bounded: users stop at duration_s and are abandoned
/// after a few seconds more.
LoadReport run_load(const LoadOptions& options);

}  // namespace isomesh::load
