#include "load_stats.h"

#include <algorithm>
#include <cmath>

namespace isomesh::load {
namespace {

constexpr std::size_t kMaxErrorExamples = 10;

double nearest_rank(const std::vector<double>& sorted, double p) {
    const auto rank = static_cast<std::size_t>(std::ceil(p * static_cast<double>(sorted.size())));
    return sorted[std::clamp<std::size_t>(rank, 1, sorted.size()) - 1];
}

template <class T>
void append(std::vector<T>& to, const std::vector<T>& from) {
    to.insert(to.end(), from.begin(), from.end());
}

}  // namespace

Percentiles percentiles(std::vector<double> samples) {
    Percentiles out;
    out.count = samples.size();
    if (samples.empty()) return out;
    std::sort(samples.begin(), samples.end());
    out.p50 = nearest_rank(samples, 0.50);
    out.p90 = nearest_rank(samples, 0.90);
    out.p99 = nearest_rank(samples, 0.99);
    out.max = samples.back();
    return out;
}

void LoadStats::record_error(std::string example) {
    if (error_examples.size() < kMaxErrorExamples) error_examples.push_back(std::move(example));
}

std::uint64_t LoadStats::error_count() const {
    std::uint64_t total = decode_errors + connection_errors;
    for (const auto& [code, count] : server_errors) total += count;
    return total;
}

void LoadStats::merge(const LoadStats& other) {
    append(first_mesh_ms, other.first_mesh_ms);
    append(created_ms, other.created_ms);
    append(first_mesh_delivery_ms, other.first_mesh_delivery_ms);
    for (const auto& [name, samples] : other.first_mesh_ms_by_entry) {
        append(first_mesh_ms_by_entry[name], samples);
    }
    append(frame_latency_ms, other.frame_latency_ms);
    append(update_latency_ms, other.update_latency_ms);
    frames += other.frames;
    keyframes += other.keyframes;
    deltas += other.deltas;
    triangles_received += other.triangles_received;
    bytes_received += other.bytes_received;
    sessions_created += other.sessions_created;
    converged += other.converged;
    updates_sent += other.updates_sent;
    resyncs += other.resyncs;
    for (const auto& [code, count] : other.server_errors) server_errors[code] += count;
    decode_errors += other.decode_errors;
    connection_errors += other.connection_errors;
    for (const std::string& example : other.error_examples) record_error(example);
}

}  // namespace isomesh::load
