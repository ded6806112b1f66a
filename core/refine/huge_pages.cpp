#include "refine/huge_pages.h"

#include <cstdlib>
#include <deque>
#include <mutex>
#include <unordered_map>

#if defined(__linux__)
#include <sys/mman.h>
#endif
#if defined(__SANITIZE_ADDRESS__)
#include <sanitizer/asan_interface.h>
#endif

namespace isomesh {
namespace {

struct Block {
    void* address = nullptr;
    std::size_t bytes = 0;
};

// Under AddressSanitizer a kept block is poisoned: an array used after its vector freed it is
// reported as with the system's allocator, though the memory is not given back.
void poison(const Block& block) {
#if defined(__SANITIZE_ADDRESS__)
    ASAN_POISON_MEMORY_REGION(block.address, block.bytes);
#else
    (void)block;
#endif
}

void unpoison(const Block& block) {
#if defined(__SANITIZE_ADDRESS__)
    ASAN_UNPOISON_MEMORY_REGION(block.address, block.bytes);
#else
    (void)block;
#endif
}

/// The blocks handed out (their sizes, which free_huge_pages is not told) and the blocks kept
/// for recycling, oldest first. Large arrays are allocated a few dozen times per refinement, so
/// one lock for the process costs nothing measurable.
class BlockRecycler {
  public:
    void* allocate(std::size_t bytes) {
        std::lock_guard lock(mutex_);
        in_use_.reserve(in_use_.size() + 1);  // may throw: before a block is taken
        Block block = take_kept(bytes);
        if (!block.address) block = fresh(bytes);
        if (block.address) in_use_.emplace(block.address, block.bytes);
        return block.address;
    }

    void free(void* address) noexcept {
        std::lock_guard lock(mutex_);
        const auto it = in_use_.find(address);
        const Block block{address, it->second};
        in_use_.erase(it);
        if (block.bytes > limit_) {
            std::free(address);
            return;
        }
        trim_to(limit_ - block.bytes);
        try {
            kept_.push_back(block);
        } catch (...) {
            std::free(address);
            return;
        }
        poison(block);
        kept_bytes_ += block.bytes;
    }

    std::size_t kept_bytes() {
        std::lock_guard lock(mutex_);
        return kept_bytes_;
    }
    std::size_t limit() {
        std::lock_guard lock(mutex_);
        return limit_;
    }
    void set_limit(std::size_t bytes) {
        std::lock_guard lock(mutex_);
        limit_ = bytes;
        trim_to(limit_);
    }
    void release() {
        std::lock_guard lock(mutex_);
        trim_to(0);
    }

  private:
    /// The smallest kept block of `bytes` to 2 `bytes` (a larger one would hold memory the next
    /// refiner's larger arrays could use), removed from the kept ones; none when there is none.
    Block take_kept(std::size_t bytes) {
        auto best = kept_.end();
        for (auto it = kept_.begin(); it != kept_.end(); ++it) {
            if (it->bytes >= bytes && it->bytes / 2 <= bytes &&
                (best == kept_.end() || it->bytes < best->bytes))
                best = it;
        }
        if (best == kept_.end()) return {};
        const Block block = *best;
        kept_.erase(best);
        kept_bytes_ -= block.bytes;
        unpoison(block);
        return block;
    }

    static Block fresh(std::size_t bytes) {
        void* address = std::aligned_alloc(kHugePageBytes, bytes);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
        // Advice only: without transparent huge pages the memory is the same, in 4 kB pages.
        if (address) (void)madvise(address, bytes, MADV_HUGEPAGE);
#endif
        return {address, bytes};
    }

    /// Frees the oldest kept blocks until at most `bytes` are kept.
    void trim_to(std::size_t bytes) noexcept {
        while (kept_bytes_ > bytes) {
            unpoison(kept_.front());
            std::free(kept_.front().address);
            kept_bytes_ -= kept_.front().bytes;
            kept_.pop_front();
        }
    }

    std::mutex mutex_;
    std::unordered_map<void*, std::size_t> in_use_;
    std::deque<Block> kept_;
    std::size_t kept_bytes_ = 0;
    std::size_t limit_ = kDefaultRecycledMemoryBytes;
};

BlockRecycler& recycler() {
    // Never destroyed: arrays of objects with static storage may be freed after it would be.
    static BlockRecycler* const instance = new BlockRecycler;
    return *instance;
}

}  // namespace

void* allocate_huge_pages(std::size_t bytes) {
    return recycler().allocate(bytes);
}

void free_huge_pages(void* block) noexcept {
    recycler().free(block);
}

std::size_t recycled_memory_bytes() {
    return recycler().kept_bytes();
}

std::size_t recycled_memory_limit() {
    return recycler().limit();
}

void set_recycled_memory_limit(std::size_t bytes) {
    recycler().set_limit(bytes);
}

void release_recycled_memory() {
    recycler().release();
}

}  // namespace isomesh
