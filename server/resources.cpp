#include "server/resources.h"

#include <cstdio>
#include <ctime>

#include <malloc.h>
#include <unistd.h>

#include "refine/array_memory.h"

namespace isomesh::server {

Clock::duration thread_cpu_time() {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return std::chrono::duration_cast<Clock::duration>(std::chrono::seconds(t.tv_sec) +
                                                       std::chrono::nanoseconds(t.tv_nsec));
}

std::uint64_t resident_bytes() {
    std::FILE* file = std::fopen("/proc/self/statm", "r");
    if (!file) return 0;
    unsigned long long size = 0, resident = 0;
    const int read = std::fscanf(file, "%llu %llu", &size, &resident);
    std::fclose(file);
    if (read != 2) return 0;
    return resident * static_cast<std::uint64_t>(sysconf(_SC_PAGE_SIZE));
}

void release_free_memory() {
    release_recycled_memory();  // the refiners' kept arrays (refine/array_memory.h)
    malloc_trim(0);
}

void configure_allocator() {
    mallopt(M_MMAP_THRESHOLD, 256 * 1024);
}

}  // namespace isomesh::server
