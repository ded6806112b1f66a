// Memory for the refiner's large arrays (triangle, vertex and record pools, queue links and
// buckets, delta logs): recycled from one refiner to the next, and backed by transparent huge
// pages where the system offers them.
//
// A refinement from scratch touches tens of megabytes of fresh memory in random order (fresh
// from the kernel in the server, which maps every allocation over 256 kB anew:
// server/resources.cpp). With 4 kB pages a quarter of its time went to page faults, one per page
// (about 9,000 per 20,000 splits), and the rest suffered TLB misses. So an array of at least 1 MB
// is allocated 2 MB-aligned and marked MADV_HUGEPAGE (Linux; transparent_hugepage "madvise" or
// "always"): one fault maps 2 MB.
//
// Fresh pages, huge or not, are still zeroed by the kernel when first touched: 12-15% of a
// refinement from scratch (bench_refine). So the blocks of freed arrays from 256 kB on (where
// glibc's heap, as isomesh-server sets it up, maps each block anew; it recycles smaller ones
// itself) are kept, up to recycled_memory().limit bytes process-wide, and handed to the next
// arrays that fit in them: a refiner that ends gives its memory, already mapped, to the next one.
// Smaller arrays use std::allocator. The contents are the same either way: only where memory
// comes from differs. The blocks kept are resident memory (the server's resident-memory check
// counts them); release_recycled_memory() gives them back to the system.
#pragma once

#include <algorithm>
#include <cstddef>
#include <memory>
#include <new>
#include <vector>

namespace isomesh {

inline constexpr std::size_t kHugePageBytes = std::size_t{2} << 20;
/// Arrays from this size on are recycled, their blocks rounded up to kRecycledBlockGrain.
inline constexpr std::size_t kRecycledArrayBytes = std::size_t{256} << 10;
inline constexpr std::size_t kRecycledBlockGrain = std::size_t{64} << 10;
/// Arrays from this size on are on huge pages, their blocks rounded up to whole huge pages (at
/// most twice their size).
inline constexpr std::size_t kHugePageArrayBytes = kHugePageBytes / 2;
/// The limit of recycled memory until set_recycled_memory_limit: about two refinements to 40,000
/// triangles, or six server sessions at their default budget of 20,000.
inline constexpr std::size_t kDefaultRecycledMemoryBytes = std::size_t{64} << 20;

/// A block for an array of `bytes` (at least kRecycledArrayBytes): the smallest kept block of
/// its rounded size to 5/4 of that, else a fresh one (on huge pages from kHugePageArrayBytes on).
/// nullptr on failure.
void* allocate_array_block(std::size_t bytes);
/// Gives back a block from allocate_array_block: kept for recycling while the blocks kept stay
/// within the limit (the oldest ones are freed first to make room), else freed.
void free_array_block(void* block) noexcept;

/// A kept block allocate_array_block(bytes) would take is there now (another thread may take it
/// first).
bool recycled_block_kept(std::size_t bytes);

/// The recycler's state (process-wide).
struct RecycledMemory {
    std::size_t kept_bytes = 0;  ///< freed blocks kept now, at most `limit`
    std::size_t limit = 0;
    std::size_t reused_blocks = 0;  ///< allocations served by a kept block, since the start
    std::size_t fresh_blocks = 0;   ///< allocations of fresh memory, since the start
};
RecycledMemory recycled_memory();
/// Sets the limit (0: nothing is kept), freeing the oldest kept blocks beyond it.
void set_recycled_memory_limit(std::size_t bytes);
/// Frees every kept block (a server whose sessions ended gives its memory back to the system).
void release_recycled_memory();

template <typename T>
class RecycledAllocator {
  public:
    using value_type = T;

    RecycledAllocator() = default;
    template <typename U>
    RecycledAllocator(const RecycledAllocator<U>&) noexcept {}

    T* allocate(std::size_t n) {
        if (n * sizeof(T) < kRecycledArrayBytes) return std::allocator<T>().allocate(n);
        if (n > std::size_t(-1) / sizeof(T)) throw std::bad_array_new_length();
        void* p = allocate_array_block(n * sizeof(T));
        if (!p) throw std::bad_alloc();
        return static_cast<T*>(p);
    }

    void deallocate(T* p, std::size_t n) noexcept {
        if (n * sizeof(T) < kRecycledArrayBytes)
            std::allocator<T>().deallocate(p, n);
        else
            free_array_block(p);
    }

    template <typename U>
    bool operator==(const RecycledAllocator<U>&) const noexcept {
        return true;
    }
};

/// A vector whose storage, once 256 kB or more, is recycled, and on huge pages from 1 MB on.
template <typename T>
using RecycledVector = std::vector<T, RecycledAllocator<T>>;

/// Room to reserve in an array: for `wanted` elements where a kept block holds them, else for
/// `fallback` (growing by doubling from there). Reserving room for a whole triangle budget at
/// once saves copying as the arrays grow, but fresh pages for all of it are zeroed when first
/// touched, in 2 MB steps: a waste for a session that stays small (a few hundred roots under a
/// budget of 20,000; with 1,000 new sessions isomesh-server spent 54% of its CPU time zeroing
/// them), and heap memory taken for the budget is resident memory the session may never use.
struct Reservation {
    Reservation(std::size_t n) : wanted(n), fallback(n) {}
    Reservation(std::size_t wanted_, std::size_t fallback_)
        : wanted(wanted_), fallback(fallback_ < wanted_ ? fallback_ : wanted_) {}
    std::size_t wanted;
    std::size_t fallback;
};

/// Reserves `room` in `array`; returns room.wanted, for make_room.
template <typename T>
std::size_t reserve(RecycledVector<T>& array, Reservation room) {
    const std::size_t bytes = room.wanted * sizeof(T);
    const bool recycled = bytes >= kRecycledArrayBytes && recycled_block_kept(bytes);
    array.reserve(recycled ? room.wanted : room.fallback);
    return room.wanted;
}

/// Room for `size` elements in `array` before it grows (a push or a resize): doubling as
/// std::vector does, except that on the way past `wanted` (the room its Reservation wanted) it
/// grows to exactly that. An array that started from the fallback room thus ends in a block of
/// the wanted size, which the next refiner's same reservation takes (a kept block is taken only
/// up to 5/4 of the array): doubled from the fallback it ended in a block up to twice as large,
/// which no later reservation took, so every refiner grew its arrays again by copying.
template <typename T>
[[gnu::noinline]] void grow_room(RecycledVector<T>& array, std::size_t size, std::size_t wanted) {
    std::size_t next = std::max(size, 2 * array.capacity());
    if (size <= wanted && next > wanted) next = wanted;
    array.reserve(next);
}
template <typename T>
inline void make_room(RecycledVector<T>& array, std::size_t size, std::size_t wanted) {
    if (size > array.capacity()) [[unlikely]]
        grow_room(array, size, wanted);
}

}  // namespace isomesh
