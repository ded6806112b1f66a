// What the server measures about itself to keep within its budgets: the CPU time of a thread (a
// session's turns are charged the CPU time of the worker running them, so a busy server does not
// fail legitimate work), the process's resident memory, and a session's memory estimated from
// what it holds.
#pragma once

#include <cstdint>

#include "server/clock.h"

namespace isomesh::server {

/// The CPU time the calling thread has used (CLOCK_THREAD_CPUTIME_ID).
Clock::duration thread_cpu_time();

/// The process's resident set size (/proc/self/statm), 0 when unknown.
std::uint64_t resident_bytes();

/// Hands freed heap memory back to the system (glibc's malloc_trim, and the arrays of ended
/// refiners kept for the next ones): after sessions end, the process's resident size falls back
/// instead of staying at its peak.
void release_free_memory();

/// Sets up glibc's allocator for a long-running server, before any thread starts: blocks of
/// 256 KiB and more (meshes' vectors, frames) are mapped on their own and unmapped when freed.
/// By default the threshold grows with every large block freed, after which such blocks come
/// from the worker threads' arenas, whose pages malloc_trim cannot free while small blocks live
/// among them (measured with two 100,000-triangle sessions: 38 MB of 114 MB still resident after
/// they ended and a trim, 11 MB with the fixed threshold; jemalloc kept more, see the report in
/// bench/soak.mjs part 5).
void configure_allocator();

/// A session's memory from what it holds. The figures are measured, not derived: the resident
/// growth of isomesh-server per triangle of converged sessions (bench/soak.mjs, "memory per
/// triangle": refiner with its split hierarchy and queues, the wire mirror, the encoder's
/// buffers), rounded up.
struct SessionMemory {
    static constexpr std::uint64_t kBaseBytes = 256 << 10;   ///< an empty session
    static constexpr std::uint64_t kBytesPerTriangle = 600;  ///< per live triangle

    /// The estimate for a session holding `triangles` triangles and `queued_bytes` of frames
    /// waiting in its subscribers' queues.
    static std::uint64_t estimate(std::uint64_t triangles, std::uint64_t queued_bytes) {
        return kBaseBytes + triangles * kBytesPerTriangle + queued_bytes;
    }
    /// What a session with this triangle budget may come to hold (its reservation).
    static std::uint64_t projected(std::uint64_t triangle_budget) {
        return estimate(triangle_budget, 0);
    }
};

}  // namespace isomesh::server
