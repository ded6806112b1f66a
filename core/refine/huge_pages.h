// Memory for the refiner's large arrays (triangle, vertex and record pools, queue links, delta
// logs), backed by transparent huge pages where the system offers them, and recycled from one
// refiner to the next.
//
// A refinement from scratch touches tens of megabytes of fresh memory in random order (fresh
// from the kernel in the server, which maps every allocation over 256 kB anew:
// server/resources.cpp). With 4 kB pages a quarter of its time went to page faults, one per page
// (about 9,000 per 20,000 splits), and the rest suffered TLB misses. So an array of at least 1 MB
// is allocated 2 MB-aligned and marked MADV_HUGEPAGE (Linux; transparent_hugepage "madvise" or
// "always"): one fault maps 2 MB. Smaller arrays use std::allocator. The contents are the same
// either way: only where memory comes from differs.
//
// Fresh pages, huge or not, are zeroed by the kernel when first touched: 12-15% of a refinement
// from scratch, and with 1,000 new sessions in isomesh-server over half of its CPU time. So the
// blocks of freed arrays are kept (up to recycled_memory_limit() bytes, process-wide) and handed
// to the next arrays that fit in them: a refiner that ends gives its memory, already mapped, to
// the next one. The blocks kept are resident memory (the server's resident-memory check counts
// them); release_recycled_memory() gives them back to the system.
#pragma once

#include <cstddef>
#include <memory>
#include <new>
#include <vector>

namespace isomesh {

inline constexpr std::size_t kHugePageBytes = std::size_t{2} << 20;
/// Arrays from this size on are rounded up to whole huge pages (at most twice their size).
inline constexpr std::size_t kHugePageArrayBytes = kHugePageBytes / 2;
/// recycled_memory_limit() until set_recycled_memory_limit: about two refinements to 40,000
/// triangles, or six server sessions at their default budget of 20,000.
inline constexpr std::size_t kDefaultRecycledMemoryBytes = std::size_t{64} << 20;

/// At least `bytes` (a multiple of kHugePageBytes), kHugePageBytes-aligned, advised as huge
/// pages: the smallest kept block of `bytes` to twice that, else a fresh one. nullptr on failure.
void* allocate_huge_pages(std::size_t bytes);
/// Gives back a block from allocate_huge_pages: kept for recycling while the blocks kept stay
/// within recycled_memory_limit() (the oldest ones are freed first to make room), else freed.
void free_huge_pages(void* block) noexcept;

/// The bytes of freed blocks kept for recycling (process-wide), at most the limit.
std::size_t recycled_memory_bytes();
std::size_t recycled_memory_limit();
/// Sets the limit (0: nothing is kept), freeing the oldest kept blocks beyond it.
void set_recycled_memory_limit(std::size_t bytes);
/// Frees every kept block (a server whose sessions ended gives its memory back to the system).
void release_recycled_memory();

template <typename T>
class HugePageAllocator {
  public:
    using value_type = T;

    HugePageAllocator() = default;
    template <typename U>
    HugePageAllocator(const HugePageAllocator<U>&) noexcept {}

    T* allocate(std::size_t n) {
        const std::size_t bytes = n * sizeof(T);
        if (bytes < kHugePageArrayBytes) return std::allocator<T>().allocate(n);
        if (n > std::size_t(-1) / sizeof(T)) throw std::bad_array_new_length();
        void* p = allocate_huge_pages(rounded(bytes));
        if (!p) throw std::bad_alloc();
        return static_cast<T*>(p);
    }

    void deallocate(T* p, std::size_t n) noexcept {
        if (n * sizeof(T) < kHugePageArrayBytes)
            std::allocator<T>().deallocate(p, n);
        else
            free_huge_pages(p);
    }

    template <typename U>
    bool operator==(const HugePageAllocator<U>&) const noexcept {
        return true;
    }

  private:
    static std::size_t rounded(std::size_t bytes) {
        return (bytes + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes;
    }
};

/// A vector whose storage, once 1 MB or more, sits on huge pages.
template <typename T>
using HugePageVector = std::vector<T, HugePageAllocator<T>>;

}  // namespace isomesh
