#include "refine/split_queue.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

namespace isomesh {
namespace {

std::vector<std::uint32_t> drain(PriorityQueue& queue) {
    std::vector<std::uint32_t> order;
    while (!queue.empty()) {
        order.push_back(queue.top());
        queue.remove(queue.top());
    }
    return order;
}

TEST(BucketQueue, bucket_of_is_monotonic_and_logarithmic) {
    BucketQueue q(QueueOrder::HighestFirst);
    EXPECT_EQ(q.bucket_of(0.0), 0u);
    EXPECT_EQ(q.bucket_of(-3.0), 0u);
    EXPECT_EQ(q.bucket_of(std::nan("")), 0u);
    EXPECT_EQ(q.bucket_of(std::ldexp(1.0, -300)), 0u);  // below 2^min_exponent
    EXPECT_EQ(q.bucket_of(INFINITY), q.bucket_count() - 1);
    std::uint32_t previous = 0;
    for (double p = 1e-60; p < 1e60; p *= 1.01) {
        const std::uint32_t b = q.bucket_of(p);
        ASSERT_GE(b, previous) << p;
        previous = b;
    }
    // 16 buckets per octave: doubling a priority moves it 16 buckets up, at any scale.
    EXPECT_EQ(q.bucket_of(2.0) - q.bucket_of(1.0), 16u);
    EXPECT_EQ(q.bucket_of(3e-20) - q.bucket_of(1.5e-20), 16u);
    EXPECT_NE(q.bucket_of(1.0), q.bucket_of(1.07));  // resolution better than 7%
}

TEST(BucketQueue, rejects_bad_settings) {
    EXPECT_THROW(BucketQueue(QueueOrder::HighestFirst, {3, -10, 10}), std::invalid_argument);
    EXPECT_THROW(BucketQueue(QueueOrder::HighestFirst, {16, 10, 10}), std::invalid_argument);
    EXPECT_THROW(BucketQueue(QueueOrder::HighestFirst, {16, -2000, 10}), std::invalid_argument);
}

TEST(BucketQueue, top_is_highest_bucket_first_in_first_out_inside) {
    BucketQueue q(QueueOrder::HighestFirst);
    q.insert(7, 1.0);
    q.insert(3, 100.0);
    q.insert(5, 1.001);  // same bucket as 7, inserted later
    q.insert(9, 0.0);
    EXPECT_EQ(q.size(), 4u);
    EXPECT_EQ(drain(q), (std::vector<std::uint32_t>{3, 7, 5, 9}));
    EXPECT_EQ(q.top(), PriorityQueue::kNone);
}

TEST(BucketQueue, lowest_first_order) {
    BucketQueue q(QueueOrder::LowestFirst);
    q.insert(1, 5.0);
    q.insert(2, 0.5);
    q.insert(3, 50.0);
    q.insert(4, 0.0);
    EXPECT_EQ(drain(q), (std::vector<std::uint32_t>{4, 2, 1, 3}));
}

TEST(BucketQueue, remove_and_update_keep_the_order) {
    BucketQueue q(QueueOrder::HighestFirst);
    for (std::uint32_t h = 0; h < 10; ++h) q.insert(h, double(h + 1));
    q.remove(9);
    q.remove(4);
    EXPECT_FALSE(q.contains(9));
    EXPECT_TRUE(q.contains(8));
    q.update(0, 1000.0);
    EXPECT_EQ(q.priority(0), 1000.0);
    EXPECT_EQ(drain(q), (std::vector<std::uint32_t>{0, 8, 7, 6, 5, 3, 2, 1}));
}

TEST(BucketQueue, extreme_priority_is_exact_within_the_top_bucket) {
    BucketQueue q(QueueOrder::HighestFirst);
    q.insert(1, 1.00);
    q.insert(2, 1.03);  // same bucket, larger
    q.insert(3, 1.01);
    EXPECT_EQ(q.extreme_priority(), 1.03);
    q.remove(2);
    EXPECT_EQ(q.extreme_priority(), 1.01);
    BucketQueue low(QueueOrder::LowestFirst);
    low.insert(1, 1.03);
    low.insert(2, 1.00);
    EXPECT_EQ(low.extreme_priority(), 1.00);
    EXPECT_EQ(BucketQueue(QueueOrder::HighestFirst).extreme_priority(), 0.0);
}

TEST(BucketQueue, visit_in_order_matches_draining) {
    BucketQueue q(QueueOrder::HighestFirst);
    std::mt19937 rng(42);
    std::uniform_real_distribution<double> exponent(-30.0, 30.0);
    for (std::uint32_t h = 0; h < 500; ++h) q.insert(h, std::exp(exponent(rng)));
    std::vector<std::uint32_t> visited;
    q.visit_in_order([&](std::uint32_t h) {
        visited.push_back(h);
        return false;
    });
    EXPECT_EQ(visited, drain(q));
    // Stopping early.
    q.insert(1, 1.0);
    q.insert(2, 2.0);
    int calls = 0;
    q.visit_in_order([&](std::uint32_t) { return ++calls == 1; });
    EXPECT_EQ(calls, 1);
}

// The approximation: an element never comes out before one more than a bucket (1/16) larger.
TEST(BucketQueue, order_is_exact_up_to_bucket_resolution) {
    BucketQueue q(QueueOrder::HighestFirst);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> exponent(-10.0, 10.0);
    std::vector<double> priority(2000);
    for (std::uint32_t h = 0; h < priority.size(); ++h)
        q.insert(h, priority[h] = std::exp(exponent(rng)));
    double lowest_so_far = INFINITY;
    while (!q.empty()) {
        const std::uint32_t h = q.top();
        ASSERT_LE(priority[h], lowest_so_far * (1.0 + 1.0 / 16.0));  // mantissa buckets
        lowest_so_far = std::min(lowest_so_far, priority[h]);
        q.remove(h);
    }
}

TEST(HeapQueue, exact_order_ties_by_handle) {
    for (QueueOrder order : {QueueOrder::HighestFirst, QueueOrder::LowestFirst}) {
        HeapQueue q(order);
        std::mt19937 rng(3);
        std::uniform_int_distribution<int> value(0, 50);
        std::vector<std::pair<double, std::uint32_t>> expected;
        for (std::uint32_t h = 0; h < 300; ++h) {
            const double p = value(rng);
            q.insert(h, p);
            expected.push_back({order == QueueOrder::HighestFirst ? -p : p, h});
        }
        for (std::uint32_t h = 0; h < 300; h += 7) {
            q.remove(h);
            expected.erase(std::find_if(expected.begin(), expected.end(),
                                        [&](const auto& e) { return e.second == h; }));
        }
        q.update(1, 1000.0);
        for (auto& e : expected)
            if (e.second == 1) e.first = order == QueueOrder::HighestFirst ? -1000.0 : 1000.0;
        std::sort(expected.begin(), expected.end());
        std::vector<std::uint32_t> visited;
        q.visit_in_order([&](std::uint32_t h) {
            visited.push_back(h);
            return false;
        });
        const std::vector<std::uint32_t> drained = drain(q);
        ASSERT_EQ(drained.size(), expected.size());
        for (std::size_t i = 0; i < drained.size(); ++i) EXPECT_EQ(drained[i], expected[i].second);
        EXPECT_EQ(visited, drained);
    }
}

// The bucket queue's exact extreme agrees with the heap's while the maximum is removed repeatedly.
TEST(HeapQueue, extreme_priority_agrees_with_bucket_queue) {
    HeapQueue heap(QueueOrder::HighestFirst);
    BucketQueue bucket(QueueOrder::HighestFirst);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> value(0.0, 1.0);
    for (std::uint32_t h = 0; h < 1000; ++h) {
        const double p = value(rng);
        heap.insert(h, p);
        bucket.insert(h, p);
    }
    for (int i = 0; i < 900; ++i) {
        ASSERT_EQ(heap.extreme_priority(), bucket.extreme_priority());
        const std::uint32_t top = heap.top();
        heap.remove(top);
        bucket.remove(top);
    }
}

}  // namespace
}  // namespace isomesh
