// What the load generator measures: per virtual user while it runs (touched by its connection's
// strand only), merged into one total at the end.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace isomesh::load {

/// p50, p90, p99 and max of a set of samples, by the nearest-rank method (the smallest sample
/// with at least p% of the samples at or below it): every reported figure is a measured one.
struct Percentiles {
    std::size_t count = 0;
    double p50 = 0;
    double p90 = 0;
    double p99 = 0;
    double max = 0;
};

/// Sorts `samples` and reads the percentiles (all zero when there are none).
Percentiles percentiles(std::vector<double> samples);

struct LoadStats {
    /// From sending `create` to the first keyframe of that session decoded and applied.
    std::vector<double> first_mesh_ms;
    /// The same samples by mix entry name: a heavy surface's phase 1 alone may take longer than
    /// a light one under load.
    std::map<std::string, std::vector<double>> first_mesh_ms_by_entry;
    /// Where the time to first mesh goes: from sending `create` to its `created` reply (the
    /// server reading, parsing and compiling the request), and from the first keyframe's server
    /// timestamp (when it was made or, cached, sent) to its arrival (the server's write queue, the
    /// network, this generator's own reading).
    std::vector<double> created_ms;
    std::vector<double> first_mesh_delivery_ms;
    /// Frame arrival (decoded) minus the frame's server timestamp, same machine, same clock.
    std::vector<double> frame_latency_ms;
    /// From sending an `update` to the first frame of that function version or a later one.
    std::vector<double> update_latency_ms;

    std::uint64_t frames = 0;
    std::uint64_t keyframes = 0;
    std::uint64_t deltas = 0;
    std::uint64_t triangles_received = 0;  ///< triangles added by frames (keyframes: all)
    std::uint64_t bytes_received = 0;      ///< binary and text messages
    std::uint64_t sessions_created = 0;
    std::uint64_t converged = 0;
    std::uint64_t updates_sent = 0;
    std::uint64_t resyncs = 0;  ///< gaps or inconsistent deltas recovered with `resync`

    std::map<std::string, std::uint64_t> server_errors;  ///< `error` replies by code
    std::uint64_t decode_errors = 0;                     ///< unreadable frames or messages
    std::uint64_t connection_errors = 0;                 ///< connections failed or ended unasked
    std::vector<std::string> error_examples;             ///< the first few, for people

    void record_error(std::string example);
    std::uint64_t error_count() const;
    void merge(const LoadStats& other);
};

}  // namespace isomesh::load
