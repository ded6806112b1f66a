// Clocks for benchmarks on a shared machine: thread CPU time counts only this thread's work,
// wall-clock time is for runs spread over several threads.
#pragma once

#include <ctime>

namespace isomesh::bench {

inline double cpu_seconds() {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

inline double wall_seconds() {
    timespec t{};
    clock_gettime(CLOCK_MONOTONIC, &t);
    return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

}  // namespace isomesh::bench
