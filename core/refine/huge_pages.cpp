#include "refine/huge_pages.h"

#include <cstdlib>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace isomesh {

void* allocate_huge_pages(std::size_t bytes) {
    void* block = std::aligned_alloc(kHugePageBytes, bytes);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    // Advice only: without transparent huge pages the memory is the same, in 4 kB pages.
    if (block) (void)madvise(block, bytes, MADV_HUGEPAGE);
#endif
    return block;
}

void free_huge_pages(void* block) noexcept {
    std::free(block);
}

}  // namespace isomesh
