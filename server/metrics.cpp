#include "server/metrics.h"

#include <cmath>
#include <cstdio>

namespace isomesh::server {
namespace {

std::string format_number(double value) {
    char text[32];
    std::snprintf(text, sizeof text, "%.9g", value);
    return text;
}

void header(std::string& out, const std::string& name, const char* type, const char* help) {
    out += "# HELP " + name + " " + help + "\n# TYPE " + name + " " + type + "\n";
}

void metric(std::string& out, const std::string& name, const char* type, const char* help,
            double value) {
    header(out, name, type, help);
    out += name + " " + format_number(value) + "\n";
}

/// 100 us to 10 s, three steps per decade.
std::vector<double> latency_bounds() {
    std::vector<double> bounds;
    for (double decade = 1e-4; decade < 10; decade *= 10) {
        for (double step : {1.0, 2.5, 5.0}) bounds.push_back(decade * step);
    }
    bounds.push_back(10);
    return bounds;
}

/// 10 us to 10 s, ten steps per decade (store latencies: fine enough to read percentiles from).
std::vector<double> fine_latency_bounds() {
    std::vector<double> bounds;
    for (int i = 0; i <= 60; ++i) bounds.push_back(1e-5 * std::pow(10.0, i / 10.0));
    return bounds;
}

}  // namespace

Histogram::Histogram(std::vector<double> bounds)
    : bounds_(std::move(bounds)), buckets_(bounds_.size() + 1) {}

void Histogram::observe(double value) {
    std::size_t i = 0;
    while (i < bounds_.size() && value > bounds_[i]) ++i;
    buckets_[i].fetch_add(1, std::memory_order_relaxed);
    count_.fetch_add(1, std::memory_order_relaxed);
    sum_.fetch_add(value, std::memory_order_relaxed);
}

void Histogram::render(std::string& out, const std::string& name) const {
    std::uint64_t cumulative = 0;
    for (std::size_t i = 0; i < buckets_.size(); ++i) {
        cumulative += buckets_[i].load(std::memory_order_relaxed);
        const std::string le = i < bounds_.size() ? format_number(bounds_[i]) : "+Inf";
        out += name + "_bucket{le=\"" + le + "\"} " + std::to_string(cumulative) + "\n";
    }
    out += name + "_sum " + format_number(sum_.load(std::memory_order_relaxed)) + "\n";
    out += name + "_count " + std::to_string(count()) + "\n";
}

Metrics::Metrics()
    : first_mesh_seconds(latency_bounds()),
      frame_latency_seconds(latency_bounds()),
      slice_seconds(latency_bounds()),
      encode_seconds(latency_bounds()),
      store_write_seconds(fine_latency_bounds()),
      store_read_seconds(fine_latency_bounds()) {
    store_up.set(1);
}

std::string Metrics::render() const {
    std::string out;
    auto gauge = [&](const char* name, const char* help, const Gauge& g) {
        metric(out, std::string("isomesh_") + name, "gauge", help, static_cast<double>(g.value()));
    };
    auto counter = [&](const char* name, const char* help, const Counter& c) {
        metric(out, std::string("isomesh_") + name + "_total", "counter", help,
               static_cast<double>(c.value()));
    };
    auto histogram = [&](const char* name, const char* help, const Histogram& h) {
        const std::string full = std::string("isomesh_") + name;
        header(out, full, "histogram", help);
        h.render(out, full);
    };
    gauge("connections", "Open WebSocket connections.", connections);
    gauge("sessions", "Live meshing sessions.", sessions);
    gauge("subscriptions", "Session subscriptions over all connections.", subscriptions);
    gauge("queued_bytes", "Output bytes queued over all connections.", queued_bytes);
    gauge("run_queue", "Sessions waiting for a worker.", run_queue);
    gauge("busy_workers", "Workers running a refinement slice.", busy_workers);
    gauge("worker_threads", "Refinement worker threads.", worker_threads);
    gauge("splits_per_second", "Splits over the last second, all sessions.", splits_per_second);
    gauge("store_up", "1 while the session store answers (or none is used), else 0.", store_up);
    gauge("http_connections", "Open plain HTTP connections.", http_connections);
    gauge("sessions_limit", "Live sessions allowed (--max-sessions).", sessions_limit);
    gauge("sessions_per_connection_limit",
          "Live sessions one connection may have created (--max-sessions-per-connection).",
          sessions_per_connection_limit);
    gauge("session_memory_limit_bytes", "Memory one session may hold (--session-memory-mb).",
          session_memory_limit_bytes);
    gauge("session_cpu_limit_seconds", "CPU time one session may use (--session-cpu-s).",
          session_cpu_limit_seconds);
    gauge("http_connections_limit", "Plain HTTP connections (--max-http-connections).",
          http_connections_limit);
    gauge("memory_limit_bytes", "Memory limit for admitting sessions (--max-memory-mb).",
          memory_limit_bytes);
    gauge("memory_reserved_bytes", "Memory the sessions' triangle budgets reserve.",
          memory_reserved_bytes);
    gauge("memory_estimate_bytes", "Memory the sessions hold, estimated.", memory_estimate_bytes);
    gauge("resident_bytes", "Resident memory of the process.", resident_bytes);
    gauge("first_mesh_cache_entries", "First meshes kept for new sessions (--first-mesh-cache).",
          first_mesh_cache_entries);
    gauge("first_mesh_cache_bytes", "Memory of the first meshes kept, estimated.",
          first_mesh_cache_bytes);
    counter("sessions_created", "Sessions created.", sessions_created);
    counter("first_mesh_cache_hits", "New sessions that sent a first mesh kept for their request.",
            first_mesh_cache_hits);
    counter("first_mesh_cache_misses", "New sessions that made their first mesh.",
            first_mesh_cache_misses);
    counter("first_mesh_cache_mismatches",
            "Kept first meshes that the session's own first step did not reproduce (its mesh "
            "was sent then).",
            first_mesh_cache_mismatches);
    counter("sessions_expired", "Sessions expired (idle or without subscribers).",
            sessions_expired);
    counter("help_items",
            "Items of a session's phase-1 loops run by idle workers helping it (--threads).",
            help_items);
    counter("splits", "Triangle bisections.", splits);
    counter("merges", "Merges (undone splits).", merges);
    counter("keyframes_sent", "Keyframes queued for sending.", keyframes_sent);
    counter("deltas_sent", "Deltas queued for sending.", deltas_sent);
    counter("deltas_dropped", "Deltas dropped for a slow connection (replaced by a keyframe).",
            deltas_dropped);
    counter("bytes_sent", "WebSocket payload bytes written.", bytes_sent);
    counter("messages_received", "Control messages received.", messages_received);
    counter("http_requests", "HTTP requests served.", http_requests);
    counter("sessions_restored", "Sessions rebuilt from the session store.", sessions_restored);
    counter("store_errors", "Session store calls that failed (store down or unreachable).",
            store_errors);
    counter("http_bad_requests", "Malformed HTTP requests and WebSocket handshakes (400).",
            http_bad_requests);
    counter("origins_refused", "WebSocket handshakes refused for their Origin (403).",
            origins_refused);
    counter("http_evicted", "HTTP connections closed to make room for new ones.", http_evicted);
    counter("accept_errors", "Failed accepts (e.g. out of file descriptors).", accept_errors);
    metric(out, "isomesh_session_cpu_seconds_total", "counter",
           "CPU time of session turns and of the workers helping them.",
           static_cast<double>(session_cpu_us.value()) / 1e6);
    header(out, "isomesh_sessions_refused_total", "counter",
           "New sessions refused: per_connection (too_many_sessions), sessions and memory "
           "(server_busy).");
    const char* reasons[] = {"per_connection", "sessions", "memory"};
    for (int i = 0; i < 3; ++i) {
        out += "isomesh_sessions_refused_total{reason=\"" + std::string(reasons[i]) + "\"} " +
               std::to_string(sessions_refused[i].value()) + "\n";
    }
    header(out, "isomesh_errors_total", "counter", "Error replies by code.");
    for (int i = 0; i < protocol::kErrorCodeCount; ++i) {
        out += "isomesh_errors_total{code=\"" +
               std::string(protocol::to_string(static_cast<protocol::ErrorCode>(i))) + "\"} " +
               std::to_string(errors[i].value()) + "\n";
    }
    histogram("first_mesh_seconds", "From a create or update to its first mesh being queued.",
              first_mesh_seconds);
    histogram("frame_latency_seconds", "From a frame's creation to its last byte written.",
              frame_latency_seconds);
    histogram("slice_seconds", "One refinement turn of one session.", slice_seconds);
    histogram("encode_seconds", "Encoding one frame.", encode_seconds);
    histogram("store_write_seconds", "One session store write (save, remove, touch).",
              store_write_seconds);
    histogram("store_read_seconds", "One session store read (claim, owners, ping).",
              store_read_seconds);
    return out;
}

}  // namespace isomesh::server
