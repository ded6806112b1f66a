// The server's clock for deadlines, timeouts and latencies.
#pragma once

#include <chrono>
#include <cstdint>

namespace isomesh::server {

using Clock = std::chrono::steady_clock;

inline double seconds_between(Clock::time_point from, Clock::time_point to) {
    return std::chrono::duration<double>(to - from).count();
}

/// Microseconds since the Unix epoch (the protocol's timestamps).
inline std::uint64_t unix_time_us() {
    using namespace std::chrono;
    return static_cast<std::uint64_t>(
        duration_cast<microseconds>(system_clock::now().time_since_epoch()).count());
}

}  // namespace isomesh::server
