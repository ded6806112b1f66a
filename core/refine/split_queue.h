// Priority queues driving refinement: which triangle to split next, which split to undo next.
//
// BucketQueue is the thesis's approximate priority queue (section 3.2.3, "Fast approximate priority
// queues"): priorities map monotonically onto a fixed array of buckets, each a doubly linked list,
// so insert, remove and peek cost O(1). Priorities in the same bucket count as equal. The map is
// logarithmic: a bucket is the exponent and the top mantissa bits of the IEEE-754 double, so each
// octave gets the same number of buckets and the relative resolution is constant (6% with the
// default 16 buckets per octave), whatever the scale of the errors. A two-level bitmap of
// non-empty buckets finds the highest (or lowest) one in a few word scans, which removes the
// thesis's O(n) worst case when the top bucket empties.
//
// HeapQueue is the exact baseline: an indexed binary heap (with decrease-key through update()).
//
// Both order elements deterministically: HeapQueue by (priority, handle), BucketQueue by bucket
// and, inside a bucket, by insertion order (first in, first out). Since the refiner performs a
// deterministic sequence of operations, either queue gives the same result whatever the step sizes.
//
// Handles are small dense integers (the refiner's triangle and split slots); the queues keep
// per-handle arrays sized to the largest handle seen.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

#include "refine/array_memory.h"

namespace isomesh {

/// Which end of the order top() returns.
enum class QueueOrder : std::uint8_t {
    HighestFirst,  // the split queue: the largest error first
    LowestFirst,   // the merge queue: the smallest error first
};

enum class QueueKind : std::uint8_t { Bucket, Heap };

class PriorityQueue {
  public:
    static constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

    virtual ~PriorityQueue() = default;

    /// Precondition: `handle` is not in the queue and is not kNone. NaN and negative priorities
    /// are stored as given and ordered as 0.
    virtual void insert(std::uint32_t handle, double priority) = 0;
    /// Precondition: `handle` is in the queue.
    virtual void remove(std::uint32_t handle) = 0;
    /// Inserts, or moves an element already present to its new priority.
    virtual void update(std::uint32_t handle, double priority) = 0;
    virtual bool contains(std::uint32_t handle) const = 0;
    /// The priority `handle` was inserted with. Precondition: contains(handle).
    virtual double priority(std::uint32_t handle) const = 0;
    virtual std::size_t size() const = 0;
    bool empty() const { return size() == 0; }
    /// The first element in queue order, or kNone when empty.
    virtual std::uint32_t top() const = 0;
    /// Calls visit(handle) for elements in queue order until it returns true (stop) or the queue
    /// is exhausted. The queue must not be modified during the visit.
    virtual void visit_in_order(const std::function<bool(std::uint32_t)>& visit) const = 0;
    /// Room for handles below `handles` at once (growing the per-handle arrays by doubling maps
    /// fresh pages again and again; see Reservation).
    virtual void reserve(Reservation handles) = 0;
    /// The exact extreme priority (the largest for HighestFirst, the smallest for LowestFirst);
    /// 0 when empty. BucketQueue scans the first bucket for it.
    virtual double extreme_priority() const = 0;
    virtual void clear() = 0;
};

struct BucketQueueSettings {
    /// Buckets per factor of two; a power of two from 1 to 1024.
    std::uint32_t buckets_per_octave = 16;
    /// Priorities below 2^min_exponent share the lowest bucket with 0, those at or above
    /// 2^max_exponent share the highest.
    int min_exponent = -256;
    int max_exponent = 256;
};

class BucketQueue final : public PriorityQueue {
  public:
    explicit BucketQueue(QueueOrder order, BucketQueueSettings settings = {});

    void insert(std::uint32_t handle, double priority) override;
    void remove(std::uint32_t handle) override;
    void update(std::uint32_t handle, double priority) override;
    bool contains(std::uint32_t handle) const override;
    double priority(std::uint32_t handle) const override;
    std::size_t size() const override { return size_; }
    std::uint32_t top() const override;
    void visit_in_order(const std::function<bool(std::uint32_t)>& visit) const override;
    double extreme_priority() const override;
    void clear() override;
    void reserve(Reservation handles) override {
        links_wanted_ = isomesh::reserve(links_, handles);
    }

    /// The bucket `priority` falls into (exposed for tests).
    std::uint32_t bucket_of(double priority) const;
    std::uint32_t bucket_count() const { return static_cast<std::uint32_t>(heads_.size()); }

  private:
    // Links by handle: 16 bytes, four to a cache line (an element's bucket is bucket_of its
    // priority, not stored).
    static constexpr std::uint32_t kNotQueued = kNone - 1;
    struct Link {
        std::uint32_t prev = kNotQueued;  // kNotQueued: not in the queue; kNone: the head
        std::uint32_t next = kNone;
        double priority = 0.0;
    };
    struct List {
        std::uint32_t head = kNone;
        std::uint32_t tail = kNone;
        // The bucket's largest (HighestFirst) or smallest (LowestFirst) priority, rescanned only
        // when the element holding it leaves: amortised O(1), since buckets are FIFO.
        double extreme = 0.0;
        bool extreme_stale = false;
    };

    std::uint32_t bucket_index(double priority) const;  // bucket_of
    std::uint32_t first_bucket() const;                 // kNone when empty
    std::uint32_t next_bucket(std::uint32_t bucket) const;
    void set_occupied(std::uint32_t bucket, bool occupied);
    bool better(double a, double b) const;  // a comes before b in queue order

    QueueOrder order_;
    std::uint32_t mantissa_bits_;
    std::int64_t first_key_;  // the bucket key of 2^min_exponent
    mutable std::vector<List> heads_;
    std::uint32_t last_bucket_ = 0;        // heads_.size() - 1
    std::vector<std::uint64_t> occupied_;  // one bit per bucket
    std::vector<std::uint64_t> summary_;   // one bit per word of occupied_
    RecycledVector<Link> links_;           // indexed by handle
    std::size_t links_wanted_ = 0;         // the room reserved for links_ (make_room)
    std::size_t size_ = 0;
};

class HeapQueue final : public PriorityQueue {
  public:
    explicit HeapQueue(QueueOrder order) : order_(order) {}

    void insert(std::uint32_t handle, double priority) override;
    void remove(std::uint32_t handle) override;
    void update(std::uint32_t handle, double priority) override;
    bool contains(std::uint32_t handle) const override;
    double priority(std::uint32_t handle) const override;
    std::size_t size() const override { return heap_.size(); }
    std::uint32_t top() const override { return heap_.empty() ? kNone : heap_.front(); }
    void visit_in_order(const std::function<bool(std::uint32_t)>& visit) const override;
    double extreme_priority() const override;
    void clear() override;
    void reserve(Reservation handles) override;

  private:
    bool before(std::uint32_t a, std::uint32_t b) const;  // a comes out of the queue before b
    void sift_up(std::size_t index);
    void sift_down(std::size_t index);
    void place(std::size_t index, std::uint32_t handle);

    QueueOrder order_;
    RecycledVector<std::uint32_t> heap_;
    RecycledVector<std::uint32_t> position_;  // indexed by handle; kNone: not in the queue
    RecycledVector<double> priority_;         // indexed by handle
};

}  // namespace isomesh
