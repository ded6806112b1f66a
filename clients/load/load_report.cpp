#include "load_report.h"

#include <cstdio>

namespace isomesh::load {
namespace {

using nlohmann::ordered_json;

ordered_json percentiles_json(const std::vector<double>& samples) {
    const Percentiles p = percentiles(samples);
    return {{"count", p.count}, {"p50", p.p50}, {"p90", p.p90}, {"p99", p.p99}, {"max", p.max}};
}

double per_second(std::uint64_t amount, double seconds) {
    return seconds > 0 ? static_cast<double>(amount) / seconds : 0.0;
}

ordered_json metrics_json(const std::optional<MetricSamples>& samples) {
    if (!samples) return nullptr;
    ordered_json out = ordered_json::object();
    for (const auto& [series, value] : *samples) out[series] = value;
    return out;
}

std::string format(const char* pattern, auto... values) {
    char line[256];
    std::snprintf(line, sizeof line, pattern, values...);
    return line;
}

std::string percentiles_line(const char* label, const std::vector<double>& samples) {
    const Percentiles p = percentiles(samples);
    return format("%-28s %9zu %9.2f %9.2f %9.2f %9.2f\n", label, p.count, p.p50, p.p90, p.p99,
                  p.max);
}

/// Series of /metrics whose value changed during the run, without histogram buckets.
std::string metrics_lines(const LoadReport& report) {
    if (!report.metrics_before || !report.metrics_after) {
        return "server /metrics: unavailable (" + report.metrics_error + ")\n";
    }
    std::string out = format("%-56s %14s %14s\n", "server /metrics (changed)", "before", "after");
    for (const auto& [series, after] : *report.metrics_after) {
        if (series.find("_bucket{") != std::string::npos) continue;
        const auto before = report.metrics_before->find(series);
        const double was = before == report.metrics_before->end() ? 0.0 : before->second;
        if (was == after) continue;
        out += format("  %-54s %14.6g %14.6g\n", series.c_str(), was, after);
    }
    return out;
}

}  // namespace

ordered_json report_json(const LoadReport& report) {
    const LoadStats& s = report.stats;
    const LoadOptions& o = report.options;
    ordered_json mix = ordered_json::array();
    for (const MixEntry& entry : o.mix) mix.push_back(entry.name);
    ordered_json server_errors = ordered_json::object();
    for (const auto& [code, count] : s.server_errors) server_errors[code] = count;
    ordered_json out;
    out["url"] = o.url.to_string();
    out["sessions"] = o.sessions;
    out["duration_s"] = o.duration_s;
    out["elapsed_s"] = report.elapsed_s;
    out["threads"] = o.threads;
    out["updates_per_s"] = o.user.updates_per_s;
    out["hold_s"] = o.user.hold_s;
    out["jitter"] = o.user.jitter;
    out["mix"] = mix;
    out["time_to_first_mesh_ms"] = percentiles_json(s.first_mesh_ms);
    ordered_json by_entry = ordered_json::object();
    for (const auto& [name, samples] : s.first_mesh_ms_by_entry) {
        by_entry[name] = percentiles_json(samples);
    }
    out["time_to_first_mesh_by_entry_ms"] = by_entry;
    out["create_to_created_ms"] = percentiles_json(s.created_ms);
    out["first_mesh_delivery_ms"] = percentiles_json(s.first_mesh_delivery_ms);
    out["frame_latency_ms"] = percentiles_json(s.frame_latency_ms);
    out["update_latency_ms"] = percentiles_json(s.update_latency_ms);
    out["frames"] = {{"decoded", s.frames}, {"keyframes", s.keyframes}, {"deltas", s.deltas}};
    out["triangles_received"] = s.triangles_received;
    out["triangles_per_s"] = per_second(s.triangles_received, report.elapsed_s);
    out["bytes_received"] = s.bytes_received;
    out["bytes_per_s"] = per_second(s.bytes_received, report.elapsed_s);
    out["sessions_created"] = s.sessions_created;
    out["converged"] = s.converged;
    out["updates_sent"] = s.updates_sent;
    out["resyncs"] = s.resyncs;
    out["errors"] = {{"total", s.error_count()},
                     {"server", server_errors},
                     {"decode", s.decode_errors},
                     {"connection", s.connection_errors},
                     {"examples", s.error_examples}};
    out["server_metrics"] = {{"before", metrics_json(report.metrics_before)},
                             {"after", metrics_json(report.metrics_after)}};
    if (!report.metrics_error.empty()) out["server_metrics"]["error"] = report.metrics_error;
    return out;
}

std::string report_table(const LoadReport& report) {
    const LoadStats& s = report.stats;
    const LoadOptions& o = report.options;
    std::string out;
    out += format(
        "isomesh-load: %zu sessions on %s for %.1f s (%.1f s elapsed), %u threads, "
        "jitter %g\n",
        o.sessions, o.url.to_string().c_str(), o.duration_s, report.elapsed_s, o.threads,
        o.user.jitter);
    out +=
        format("%-28s %9s %9s %9s %9s %9s\n", "latency (ms)", "count", "p50", "p90", "p99", "max");
    out += percentiles_line("time to first mesh", s.first_mesh_ms);
    for (const auto& [name, samples] : s.first_mesh_ms_by_entry) {
        out += percentiles_line(("  " + name).c_str(), samples);
    }
    out += percentiles_line("  create to created", s.created_ms);
    out += percentiles_line("  first mesh delivery", s.first_mesh_delivery_ms);
    out += percentiles_line("frame latency", s.frame_latency_ms);
    out += percentiles_line("update to frame", s.update_latency_ms);
    out += format("%-28s %9llu (%llu keyframes, %llu deltas)\n", "frames decoded",
                  static_cast<unsigned long long>(s.frames),
                  static_cast<unsigned long long>(s.keyframes),
                  static_cast<unsigned long long>(s.deltas));
    out += format("%-28s %9llu (%.0f per s)\n", "triangles received",
                  static_cast<unsigned long long>(s.triangles_received),
                  per_second(s.triangles_received, report.elapsed_s));
    out += format("%-28s %9llu (%.0f per s)\n", "bytes received",
                  static_cast<unsigned long long>(s.bytes_received),
                  per_second(s.bytes_received, report.elapsed_s));
    out += format("%-28s %9llu (%llu converged, %llu updates sent)\n", "sessions created",
                  static_cast<unsigned long long>(s.sessions_created),
                  static_cast<unsigned long long>(s.converged),
                  static_cast<unsigned long long>(s.updates_sent));
    out += format("%-28s %9llu (decode %llu, connection %llu, resyncs %llu)\n", "errors",
                  static_cast<unsigned long long>(s.error_count()),
                  static_cast<unsigned long long>(s.decode_errors),
                  static_cast<unsigned long long>(s.connection_errors),
                  static_cast<unsigned long long>(s.resyncs));
    for (const auto& [code, count] : s.server_errors) {
        out += format("  server error %-12s %9llu\n", code.c_str(),
                      static_cast<unsigned long long>(count));
    }
    for (const std::string& example : s.error_examples) out += "  e.g. " + example + "\n";
    out += metrics_lines(report);
    return out;
}

}  // namespace isomesh::load
