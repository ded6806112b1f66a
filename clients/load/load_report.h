// The load generator's report, as JSON (for scripts) and as a table (for people).
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "load_run.h"

namespace isomesh::load {

/// Keys: url, sessions, duration_s, elapsed_s, threads, updates_per_s, hold_s, mix (names),
/// time_to_first_mesh_ms / frame_latency_ms / update_latency_ms ({count, p50, p90, p99, max}),
/// time_to_first_mesh_by_entry_ms {entry name: the same}, create_to_created_ms and
/// first_mesh_delivery_ms (parts of the time to first mesh, load_stats.h; the same form),
/// frames {decoded, keyframes, deltas}, triangles_received, triangles_per_s, bytes_received,
/// bytes_per_s, sessions_created, converged, updates_sent, resyncs,
/// errors {total, server {code: count}, decode, connection, examples},
/// server_metrics {before, after, error?} (every series of /metrics; null when unreadable).
nlohmann::ordered_json report_json(const LoadReport& report);

/// A few aligned lines: the figures above, and for the server's metrics the series that
/// changed during the run (histogram buckets left out).
std::string report_table(const LoadReport& report);

}  // namespace isomesh::load
