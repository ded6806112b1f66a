// Bucketed approximate priority queue (the thesis, section 3.2.3) and an indexed binary heap
// (Williams, "Algorithm 232: Heapsort", CACM 1964) as its exact baseline.
#include "refine/split_queue.h"

#include <bit>
#include <cassert>
#include <cmath>
#include <queue>
#include <stdexcept>

namespace isomesh {
namespace {

constexpr int kMantissaBits = 52;
constexpr int kExponentBias = 1023;

double ordering_value(double priority) {
    return priority > 0.0 ? priority : 0.0;
}  // NaN -> 0

template <typename T>
void grow_to(RecycledVector<T>& v, std::uint32_t handle, const T& fill) {
    if (handle >= v.size()) v.resize(static_cast<std::size_t>(handle) + 1, fill);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// BucketQueue

BucketQueue::BucketQueue(QueueOrder order, BucketQueueSettings settings) : order_(order) {
    const std::uint32_t per_octave = settings.buckets_per_octave;
    if (per_octave == 0 || per_octave > 1024 || !std::has_single_bit(per_octave))
        throw std::invalid_argument(
            "BucketQueue: buckets_per_octave must be a power of two <= 1024");
    if (settings.min_exponent < -1022 || settings.max_exponent > 1023 ||
        settings.min_exponent >= settings.max_exponent)
        throw std::invalid_argument(
            "BucketQueue: need -1022 <= min_exponent < max_exponent <= 1023");
    mantissa_bits_ = static_cast<std::uint32_t>(std::countr_zero(per_octave));
    first_key_ = static_cast<std::int64_t>(settings.min_exponent + kExponentBias) << mantissa_bits_;
    // Bucket 0 holds zero and everything below 2^min_exponent; then one bucket per key.
    const std::size_t count =
        static_cast<std::size_t>(settings.max_exponent - settings.min_exponent) * per_octave + 1;
    heads_.assign(count, List{});
    last_bucket_ = static_cast<std::uint32_t>(count - 1);
    occupied_.assign((count + 63) / 64, 0);
    summary_.assign((occupied_.size() + 63) / 64, 0);
}

std::uint32_t BucketQueue::bucket_of(double priority) const {
    return bucket_index(priority);
}

// bucket_of, inlined into insert.
inline std::uint32_t BucketQueue::bucket_index(double priority) const {
    const double p = ordering_value(priority);
    if (p == 0.0) return 0;
    const std::uint64_t bits = std::bit_cast<std::uint64_t>(p);
    // For positive doubles the bit pattern is monotonic in the value; its top bits are the
    // exponent followed by the leading mantissa bits, a piecewise linear approximation of log2.
    const auto key = static_cast<std::int64_t>(bits >> (kMantissaBits - mantissa_bits_));
    const std::int64_t bucket = key - first_key_ + 1;
    const auto last = static_cast<std::int64_t>(last_bucket_);
    if (bucket < 1) return 0;
    return static_cast<std::uint32_t>(bucket > last ? last : bucket);
}

inline bool BucketQueue::better(double a, double b) const {
    return order_ == QueueOrder::HighestFirst ? a > b : a < b;
}

inline void BucketQueue::set_occupied(std::uint32_t bucket, bool occupied) {
    const std::uint32_t word = bucket / 64;
    const std::uint64_t bit = std::uint64_t{1} << (bucket % 64);
    if (occupied) {
        occupied_[word] |= bit;
        summary_[word / 64] |= std::uint64_t{1} << (word % 64);
    } else {
        occupied_[word] &= ~bit;
        if (occupied_[word] == 0) summary_[word / 64] &= ~(std::uint64_t{1} << (word % 64));
    }
}

void BucketQueue::insert(std::uint32_t handle, double priority) {
    assert(handle < kNotQueued);
    if (handle >= links_.size()) {
        make_room(links_, std::size_t{handle} + 1, links_wanted_);
        // Mostly a new slot, the next handle: one push rather than resize's general fill.
        if (handle == links_.size())
            links_.push_back(Link{});
        else
            links_.resize(std::size_t{handle} + 1, Link{});
        // Handles are slots, mostly new ones in increasing order: the line of the links a few
        // inserts ahead is asked for now.
        if (std::size_t{handle} + 16 < links_.capacity())
            __builtin_prefetch(links_.data() + handle + 16, 1);
    }
    Link& link = links_[handle];
    assert(link.prev == kNotQueued && "insert: handle already queued");
    const std::uint32_t bucket = bucket_index(priority);
    List& list = heads_[bucket];
    const double p = ordering_value(priority);
    if (list.head == kNone) {
        list.extreme = p;
        list.extreme_stale = false;
    } else if (!list.extreme_stale && better(p, list.extreme)) {
        list.extreme = p;
    }
    link = Link{list.tail, kNone, priority};
    if (list.tail != kNone)
        links_[list.tail].next = handle;
    else
        list.head = handle;
    list.tail = handle;
    set_occupied(bucket, true);
    ++size_;
}

void BucketQueue::remove(std::uint32_t handle) {
    assert(contains(handle));
    Link& link = links_[handle];
    const std::uint32_t bucket = bucket_index(link.priority);  // as when it was inserted
    List& list = heads_[bucket];
    if (link.prev != kNone)
        links_[link.prev].next = link.next;
    else
        list.head = link.next;
    if (link.next != kNone)
        links_[link.next].prev = link.prev;
    else
        list.tail = link.prev;
    if (list.head == kNone) set_occupied(bucket, false);
    if (ordering_value(link.priority) == list.extreme) list.extreme_stale = true;
    link = Link{};
    --size_;
}

void BucketQueue::update(std::uint32_t handle, double priority) {
    if (contains(handle)) remove(handle);
    insert(handle, priority);
}

bool BucketQueue::contains(std::uint32_t handle) const {
    return handle < links_.size() && links_[handle].prev != kNotQueued;
}

double BucketQueue::priority(std::uint32_t handle) const {
    assert(contains(handle));
    return links_[handle].priority;
}

std::uint32_t BucketQueue::first_bucket() const {
    if (size_ == 0) return kNone;
    if (order_ == QueueOrder::HighestFirst) {
        for (std::size_t s = summary_.size(); s-- > 0;) {
            if (summary_[s] == 0) continue;
            const std::size_t word =
                s * 64 + 63 - static_cast<std::size_t>(std::countl_zero(summary_[s]));
            return static_cast<std::uint32_t>(word * 64 + 63 - std::countl_zero(occupied_[word]));
        }
    } else {
        for (std::size_t s = 0; s < summary_.size(); ++s) {
            if (summary_[s] == 0) continue;
            const std::size_t word =
                s * 64 + static_cast<std::size_t>(std::countr_zero(summary_[s]));
            return static_cast<std::uint32_t>(word * 64 + std::countr_zero(occupied_[word]));
        }
    }
    assert(false && "size_ > 0 but no bucket occupied");
    return kNone;
}

std::uint32_t BucketQueue::next_bucket(std::uint32_t bucket) const {
    // Used only by visit_in_order, where a plain scan of the bitmap words is fast enough.
    if (order_ == QueueOrder::HighestFirst) {
        for (std::uint32_t b = bucket; b-- > 0;) {
            const std::uint64_t word = occupied_[b / 64] & ((std::uint64_t{2} << (b % 64)) - 1);
            if (word != 0)
                return (b / 64) * 64 + 63 - static_cast<std::uint32_t>(std::countl_zero(word));
            b = (b / 64) * 64;  // skip the rest of this word
        }
    } else {
        for (std::uint32_t b = bucket + 1; b < heads_.size();) {
            const std::uint64_t word = occupied_[b / 64] & (~std::uint64_t{0} << (b % 64));
            if (word != 0)
                return (b / 64) * 64 + static_cast<std::uint32_t>(std::countr_zero(word));
            b = (b / 64 + 1) * 64;
        }
    }
    return kNone;
}

std::uint32_t BucketQueue::top() const {
    const std::uint32_t bucket = first_bucket();
    return bucket == kNone ? kNone : heads_[bucket].head;
}

void BucketQueue::visit_in_order(const std::function<bool(std::uint32_t)>& visit) const {
    for (std::uint32_t b = first_bucket(); b != kNone; b = next_bucket(b))
        for (std::uint32_t h = heads_[b].head; h != kNone; h = links_[h].next)
            if (visit(h)) return;
}

double BucketQueue::extreme_priority() const {
    const std::uint32_t bucket = first_bucket();
    if (bucket == kNone) return 0.0;
    List& list = heads_[bucket];
    if (list.extreme_stale) {
        list.extreme = ordering_value(links_[list.head].priority);
        for (std::uint32_t h = links_[list.head].next; h != kNone; h = links_[h].next)
            if (better(ordering_value(links_[h].priority), list.extreme))
                list.extreme = ordering_value(links_[h].priority);
        list.extreme_stale = false;
    }
    return list.extreme;
}

void BucketQueue::clear() {
    std::fill(heads_.begin(), heads_.end(), List{});
    std::fill(occupied_.begin(), occupied_.end(), 0);
    std::fill(summary_.begin(), summary_.end(), 0);
    links_.clear();
    size_ = 0;
}

// ---------------------------------------------------------------------------------------------
// HeapQueue

bool HeapQueue::before(std::uint32_t a, std::uint32_t b) const {
    const double pa = ordering_value(priority_[a]);
    const double pb = ordering_value(priority_[b]);
    if (pa != pb) return order_ == QueueOrder::HighestFirst ? pa > pb : pa < pb;
    return a < b;
}

void HeapQueue::place(std::size_t index, std::uint32_t handle) {
    heap_[index] = handle;
    position_[handle] = static_cast<std::uint32_t>(index);
}

void HeapQueue::sift_up(std::size_t index) {
    const std::uint32_t handle = heap_[index];
    while (index > 0) {
        const std::size_t parent = (index - 1) / 2;
        if (!before(handle, heap_[parent])) break;
        place(index, heap_[parent]);
        index = parent;
    }
    place(index, handle);
}

void HeapQueue::sift_down(std::size_t index) {
    const std::uint32_t handle = heap_[index];
    const std::size_t n = heap_.size();
    for (;;) {
        std::size_t child = 2 * index + 1;
        if (child >= n) break;
        if (child + 1 < n && before(heap_[child + 1], heap_[child])) ++child;
        if (!before(heap_[child], handle)) break;
        place(index, heap_[child]);
        index = child;
    }
    place(index, handle);
}

void HeapQueue::insert(std::uint32_t handle, double priority) {
    assert(handle != kNone && !contains(handle));
    grow_to(position_, handle, kNone);
    grow_to(priority_, handle, 0.0);
    priority_[handle] = priority;
    heap_.push_back(handle);
    position_[handle] = static_cast<std::uint32_t>(heap_.size() - 1);
    sift_up(heap_.size() - 1);
}

void HeapQueue::remove(std::uint32_t handle) {
    assert(contains(handle));
    const std::size_t index = position_[handle];
    position_[handle] = kNone;
    const std::uint32_t last = heap_.back();
    heap_.pop_back();
    if (index == heap_.size()) return;
    place(index, last);
    sift_up(index);
    sift_down(position_[last]);
}

void HeapQueue::update(std::uint32_t handle, double priority) {
    if (!contains(handle)) {
        insert(handle, priority);
        return;
    }
    priority_[handle] = priority;
    sift_up(position_[handle]);
    sift_down(position_[handle]);
}

bool HeapQueue::contains(std::uint32_t handle) const {
    return handle < position_.size() && position_[handle] != kNone;
}

double HeapQueue::priority(std::uint32_t handle) const {
    assert(contains(handle));
    return priority_[handle];
}

void HeapQueue::visit_in_order(const std::function<bool(std::uint32_t)>& visit) const {
    // Best-first walk of the heap tree: O(k log k) for the first k elements.
    auto later = [this](std::size_t a, std::size_t b) { return before(heap_[b], heap_[a]); };
    std::priority_queue<std::size_t, std::vector<std::size_t>, decltype(later)> frontier(later);
    if (!heap_.empty()) frontier.push(0);
    while (!frontier.empty()) {
        const std::size_t index = frontier.top();
        frontier.pop();
        if (visit(heap_[index])) return;
        for (std::size_t child = 2 * index + 1; child <= 2 * index + 2; ++child)
            if (child < heap_.size()) frontier.push(child);
    }
}

double HeapQueue::extreme_priority() const {
    return heap_.empty() ? 0.0 : ordering_value(priority_[heap_.front()]);
}

void HeapQueue::reserve(Reservation handles) {
    isomesh::reserve(heap_, handles);
    isomesh::reserve(position_, handles);
    isomesh::reserve(priority_, handles);
}

void HeapQueue::clear() {
    heap_.clear();
    position_.clear();
    priority_.clear();
}

}  // namespace isomesh
