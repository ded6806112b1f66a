#include "refine/huge_pages.h"

#include <cstdlib>
#include <utility>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace isomesh {
namespace {

/// Freed blocks kept by one thread, most recently freed last; freed with the thread.
class BlockCache {
  public:
    ~BlockCache() {
        for (const auto& [block, bytes] : blocks_) std::free(block);
    }
    void* take(std::size_t bytes) {
        for (std::size_t i = blocks_.size(); i-- > 0;) {
            if (blocks_[i].second != bytes) continue;
            void* block = blocks_[i].first;
            blocks_.erase(blocks_.begin() + static_cast<std::ptrdiff_t>(i));
            total_ -= bytes;
            return block;
        }
        return nullptr;
    }
    void put(void* block, std::size_t bytes) noexcept {
        // The oldest blocks make room; a block larger than the whole cache is freed.
        while (!blocks_.empty() && total_ + bytes > kHugePageCacheBytes) {
            std::free(blocks_.front().first);
            total_ -= blocks_.front().second;
            blocks_.erase(blocks_.begin());
        }
        if (bytes > kHugePageCacheBytes || blocks_.size() == blocks_.capacity()) {
            std::free(block);
            return;
        }
        blocks_.emplace_back(block, bytes);
        total_ += bytes;
    }
    BlockCache() { blocks_.reserve(kHugePageCacheBytes / kHugePageBytes); }

  private:
    std::vector<std::pair<void*, std::size_t>> blocks_;
    std::size_t total_ = 0;
};

thread_local BlockCache cache;

}  // namespace

void* allocate_huge_pages(std::size_t bytes) {
    if (void* block = cache.take(bytes)) return block;
    void* block = std::aligned_alloc(kHugePageBytes, bytes);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    // Advice only: without transparent huge pages the memory is the same, in 4 kB pages.
    if (block) (void)madvise(block, bytes, MADV_HUGEPAGE);
#endif
    return block;
}

void free_huge_pages(void* block, std::size_t bytes) noexcept {
    cache.put(block, bytes);
}

}  // namespace isomesh
