// The server's metrics, exported at GET /metrics in the Prometheus text format (version 0.0.4):
// lock-free counters, gauges and fixed-bucket histograms updated from any thread.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "protocol/errors.h"

namespace isomesh::server {

class Counter {
  public:
    void add(std::uint64_t n = 1) { value_.fetch_add(n, std::memory_order_relaxed); }
    std::uint64_t value() const { return value_.load(std::memory_order_relaxed); }

  private:
    std::atomic<std::uint64_t> value_{0};
};

class Gauge {
  public:
    void add(std::int64_t n) { value_.fetch_add(n, std::memory_order_relaxed); }
    void set(std::int64_t v) { value_.store(v, std::memory_order_relaxed); }
    std::int64_t value() const { return value_.load(std::memory_order_relaxed); }

  private:
    std::atomic<std::int64_t> value_{0};
};

/// Observations counted in buckets with upper bounds `bounds` (ascending), plus +Inf.
class Histogram {
  public:
    explicit Histogram(std::vector<double> bounds);
    void observe(double value);
    /// Prometheus lines for the metric `name` (with _bucket, _sum and _count).
    void render(std::string& out, const std::string& name) const;
    std::uint64_t count() const { return count_.load(std::memory_order_relaxed); }

  private:
    std::vector<double> bounds_;
    std::vector<std::atomic<std::uint64_t>> buckets_;  // one per bound, then +Inf
    std::atomic<std::uint64_t> count_{0};
    std::atomic<double> sum_{0};
};

struct Metrics {
    Metrics();

    // gauges
    Gauge connections;
    Gauge sessions;
    Gauge subscriptions;
    Gauge queued_bytes;  ///< output bytes waiting in every connection's queue
    Gauge run_queue;     ///< sessions waiting for a worker
    Gauge busy_workers;  ///< workers running a session slice
    Gauge worker_threads;
    Gauge splits_per_second;              ///< over the last second, all sessions
    Gauge store_up;                       ///< 1 while the session store answers (or there is none)
    Gauge http_connections;               ///< plain HTTP connections (not upgraded)
    Gauge sessions_limit;                 ///< --max-sessions
    Gauge sessions_per_connection_limit;  ///< --max-sessions-per-connection
    Gauge session_memory_limit_bytes;     ///< --session-memory-mb
    Gauge session_cpu_limit_seconds;      ///< --session-cpu-s
    Gauge http_connections_limit;         ///< --max-http-connections
    Gauge memory_limit_bytes;             ///< --max-memory-mb, resolved
    Gauge memory_reserved_bytes;          ///< the sessions' reservations (triangle budgets)
    Gauge memory_estimate_bytes;     ///< what the sessions hold, estimated (server/resources.h)
    Gauge resident_bytes;            ///< the process's resident set
    Gauge first_mesh_cache_entries;  ///< server/first_mesh_cache.h
    Gauge first_mesh_cache_bytes;

    // counters
    Counter sessions_created;
    Counter sessions_expired;
    Counter splits;
    Counter merges;
    Counter keyframes_sent;
    Counter deltas_sent;
    Counter deltas_dropped;  ///< replaced by a keyframe (backpressure)
    Counter bytes_sent;
    Counter messages_received;
    Counter http_requests;
    Counter sessions_restored;  ///< rebuilt from the session store
    Counter store_errors;       ///< session store calls that failed
    Counter http_bad_requests;  ///< malformed HTTP requests and WebSocket handshakes (400)
    Counter origins_refused;    ///< WebSocket handshakes from an Origin not allowed (403)
    Counter http_evicted;       ///< HTTP connections closed to make room (limit, EMFILE)
    Counter accept_errors;      ///< failed accept() calls (e.g. out of file descriptors)
    Counter session_cpu_us;     ///< CPU time of session turns and their helpers, microseconds
    /// Items of a session's parallel loop (phase 1) run by an idle worker helping it.
    Counter help_items;
    Counter first_mesh_cache_hits;    ///< new sessions that sent a cached first mesh
    Counter first_mesh_cache_misses;  ///< new sessions that made their first mesh
    /// Cached first meshes that the session's own first step did not reproduce (then sent).
    Counter first_mesh_cache_mismatches;
    std::array<Counter, protocol::kErrorCodeCount> errors;
    /// New sessions refused, by reason (sessions_refused_total{reason=...}).
    static constexpr int kRefusedPerConnection = 0, kRefusedSessions = 1, kRefusedMemory = 2;
    std::array<Counter, 3> sessions_refused;

    // histograms, seconds
    Histogram first_mesh_seconds;     ///< from a version's request to its keyframe being queued
    Histogram frame_latency_seconds;  ///< from a frame's creation to its last byte written
    Histogram slice_seconds;          ///< one refinement turn of one session
    Histogram encode_seconds;         ///< encoding one frame (Draco and id lists)
    Histogram store_write_seconds;    ///< one session store write (save, remove, touch)
    Histogram store_read_seconds;     ///< one session store read (claim, owners, ping)

    /// Every metric in the Prometheus text exposition format.
    std::string render() const;
};

}  // namespace isomesh::server
