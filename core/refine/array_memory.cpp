#include "refine/array_memory.h"

#include <algorithm>
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

constexpr std::size_t kPageBytes = 4096;

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

/// The blocks handed out (their sizes, which free_array_block is not told) and the blocks kept
/// for recycling, oldest first. Large arrays are allocated a few dozen times per refinement, so
/// one lock for the process costs nothing measurable.
class BlockRecycler {
  public:
    void* allocate(std::size_t bytes) {
        bytes = rounded(bytes);
        std::lock_guard lock(mutex_);
        in_use_.reserve(in_use_.size() + 1);  // may throw: before a block is taken
        Block block = take_kept(bytes);
        if (block.address)
            ++state_.reused_blocks;
        else
            block = fresh(bytes);
        if (block.address) in_use_.emplace(block.address, block.bytes);
        return block.address;
    }

    void free(void* address) noexcept {
        std::lock_guard lock(mutex_);
        const auto it = in_use_.find(address);
        const Block block{address, it->second};
        in_use_.erase(it);
        if (block.bytes > state_.limit) {
            std::free(address);
            return;
        }
        trim_to(state_.limit - block.bytes);
        try {
            kept_.push_back(block);
        } catch (...) {
            std::free(address);
            return;
        }
        poison(block);
        state_.kept_bytes += block.bytes;
    }

    bool kept(std::size_t bytes) {
        bytes = rounded(bytes);
        std::lock_guard lock(mutex_);
        return std::any_of(kept_.begin(), kept_.end(),
                           [&](const Block& b) { return fits(b, bytes); });
    }

    RecycledMemory state() {
        std::lock_guard lock(mutex_);
        return state_;
    }
    void set_limit(std::size_t bytes) {
        std::lock_guard lock(mutex_);
        state_.limit = bytes;
        trim_to(state_.limit);
    }
    void release() {
        std::lock_guard lock(mutex_);
        trim_to(0);
    }

  private:
    /// The smallest kept block of `bytes` to 5/4 `bytes`, removed from the kept ones; none when
    /// there is none. A larger block would hold resident memory (the pages its last array
    /// touched) that the array does not need, beyond what a session's memory estimate allows.
    Block take_kept(std::size_t bytes) {
        auto best = kept_.end();
        for (auto it = kept_.begin(); it != kept_.end(); ++it) {
            if (fits(*it, bytes) && (best == kept_.end() || it->bytes < best->bytes)) best = it;
        }
        if (best == kept_.end()) return {};
        const Block block = *best;
        kept_.erase(best);
        state_.kept_bytes -= block.bytes;
        unpoison(block);
        return block;
    }

    static bool fits(const Block& block, std::size_t bytes) {
        return block.bytes >= bytes && block.bytes <= bytes + bytes / 4;
    }

    static std::size_t rounded(std::size_t bytes) {
        const std::size_t grain =
            bytes < kHugePageArrayBytes ? kRecycledBlockGrain : kHugePageBytes;
        return (bytes + grain - 1) / grain * grain;
    }

    Block fresh(std::size_t bytes) {
        const bool huge = bytes >= kHugePageBytes;  // rounded: whole huge pages
        void* address = std::aligned_alloc(huge ? kHugePageBytes : kPageBytes, bytes);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
        // Advice only: without transparent huge pages the memory is the same, in 4 kB pages.
        if (address && huge) (void)madvise(address, bytes, MADV_HUGEPAGE);
#endif
        if (address) ++state_.fresh_blocks;
        return {address, bytes};
    }

    /// Frees the oldest kept blocks until at most `bytes` are kept.
    void trim_to(std::size_t bytes) noexcept {
        while (state_.kept_bytes > bytes) {
            unpoison(kept_.front());
            std::free(kept_.front().address);
            state_.kept_bytes -= kept_.front().bytes;
            kept_.pop_front();
        }
    }

    std::mutex mutex_;
    std::unordered_map<void*, std::size_t> in_use_;
    std::deque<Block> kept_;
    RecycledMemory state_{.limit = kDefaultRecycledMemoryBytes};
};

BlockRecycler& recycler() {
    // Never destroyed: arrays of objects with static storage may be freed after it would be.
    static BlockRecycler* const instance = new BlockRecycler;
    return *instance;
}

}  // namespace

void* allocate_array_block(std::size_t bytes) {
    return recycler().allocate(bytes);
}

void free_array_block(void* block) noexcept {
    recycler().free(block);
}

bool recycled_block_kept(std::size_t bytes) {
    return recycler().kept(bytes);
}

RecycledMemory recycled_memory() {
    return recycler().state();
}

void set_recycled_memory_limit(std::size_t bytes) {
    recycler().set_limit(bytes);
}

void release_recycled_memory() {
    recycler().release();
}

}  // namespace isomesh
