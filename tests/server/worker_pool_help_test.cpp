// The worker pool as an executor of help offers (server/worker_pool.h, work/helpers.h): an idle
// worker helps a running task's loop and /metrics counts its items; a queued task goes before an
// offer, and a helper goes back to a task queued meanwhile after the item it runs; stop() recalls
// helpers. Every wait is on an event (a generous limit only turns a hang into a failure).
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "server/worker_pool.h"

namespace isomesh::server {
namespace {

using namespace std::chrono_literals;

/// A one-way event.
class Flag {
  public:
    void set() {
        std::lock_guard lock(mutex_);
        set_ = true;
        changed_.notify_all();
    }
    bool is_set() const {
        std::lock_guard lock(mutex_);
        return set_;
    }
    /// False if it was not set within 20 s (a hang).
    bool wait() const {
        std::unique_lock lock(mutex_);
        return changed_.wait_for(lock, 20s, [this] { return set_; });
    }

  private:
    mutable std::mutex mutex_;
    mutable std::condition_variable changed_;
    bool set_ = false;
};

/// A task running `body` in its one turn.
struct BodyTask : Task {
    explicit BodyTask(std::function<void()> body) : body(std::move(body)) {}
    bool run_slice() override {
        body();
        ran.set();
        return false;
    }
    std::function<void()> body;
    Flag ran;
};

/// A loop of `count` items offered to the pool's workers (at most `helpers` of them) by the task
/// running it; `item(i, slot)` runs each.
struct HelpedLoop {
    HelpedLoop(std::size_t count, std::function<void(std::size_t, unsigned)> item)
        : runs(count), item(std::move(item)) {}
    void run(WorkerPool& pool, unsigned helpers) {
        const HelpWork work = [this](unsigned slot, const Recall& recalled) {
            std::size_t items = 0;
            while (!recalled()) {
                const std::size_t i = next++;
                if (i >= runs.size()) break;
                item(i, slot);
                ++runs[i];
                if (slot != 0) ++by_helpers;
                ++items;
            }
            return items;
        };
        run_helped(&pool, helpers, work);
    }
    bool each_ran_once() const {
        for (const auto& r : runs)
            if (r != 1) return false;
        return true;
    }
    std::vector<std::atomic<int>> runs;
    std::function<void(std::size_t, unsigned)> item;
    std::atomic<std::size_t> next{0};
    std::atomic<std::size_t> by_helpers{0};
};

TEST(WorkerPool, offer_is_taken_by_an_idle_worker_and_counted) {
    Metrics metrics;
    WorkerPool pool(2, &metrics);
    Flag helped;
    bool caller_waited = true;
    HelpedLoop loop(20, [&](std::size_t, unsigned slot) {
        if (slot == 0) {
            caller_waited = caller_waited && helped.wait();  // until the idle worker ran one
        } else {
            helped.set();
        }
    });
    auto task = std::make_shared<BodyTask>([&] { loop.run(pool, 1); });
    pool.schedule(task);
    ASSERT_TRUE(pool.wait_idle(Clock::now() + 20s));  // the helper has counted its items too
    EXPECT_TRUE(caller_waited);
    EXPECT_TRUE(loop.each_ran_once());
    EXPECT_GT(loop.by_helpers, 0u);
    EXPECT_EQ(metrics.help_items.value(), loop.by_helpers);
}

TEST(WorkerPool, offer_waits_while_a_task_is_queued) {
    Metrics metrics;
    WorkerPool pool(2, &metrics);
    Flag b_running, release_b, c_ran;
    auto b = std::make_shared<BodyTask>([&] {
        b_running.set();
        EXPECT_TRUE(release_b.wait());
    });
    pool.schedule(b);
    ASSERT_TRUE(b_running.wait());
    // A offers its loop while B holds the other worker, and waits in its first item for C.
    Flag a_offered;
    HelpedLoop loop(4, [&](std::size_t, unsigned slot) {
        if (slot != 0) return;
        a_offered.set();
        EXPECT_TRUE(c_ran.wait());
    });
    auto a = std::make_shared<BodyTask>([&] { loop.run(pool, 1); });
    pool.schedule(a);
    ASSERT_TRUE(a_offered.wait());
    std::size_t help_before_c = ~std::size_t{0};
    auto c = std::make_shared<BodyTask>([&] {
        help_before_c = loop.by_helpers;
        c_ran.set();
    });
    pool.schedule(c);
    release_b.set();  // B's worker now finds both C queued and A's offer: C first
    ASSERT_TRUE(pool.wait_idle(Clock::now() + 20s));
    ASSERT_TRUE(a->ran.is_set() && c->ran.is_set());
    EXPECT_EQ(help_before_c, 0u);
    EXPECT_TRUE(loop.each_ran_once());
}

TEST(WorkerPool, helper_goes_back_to_a_queued_task_after_its_item) {
    Metrics metrics;
    WorkerPool pool(2, &metrics);
    Flag helping, c_queued, c_ran;
    HelpedLoop loop(10, [&](std::size_t, unsigned slot) {
        if (slot == 0) {
            EXPECT_TRUE(c_ran.wait());  // the caller's first item ends once C ran
        } else if (!helping.is_set()) {
            helping.set();
            EXPECT_TRUE(c_queued.wait());
        }
    });
    auto a = std::make_shared<BodyTask>([&] { loop.run(pool, 1); });
    pool.schedule(a);
    ASSERT_TRUE(helping.wait());
    auto c = std::make_shared<BodyTask>([&] { c_ran.set(); });
    pool.schedule(c);  // both workers busy: queued
    c_queued.set();
    ASSERT_TRUE(pool.wait_idle(Clock::now() + 20s));
    // The helper ran its one item and went to C; the caller ran the rest.
    EXPECT_EQ(loop.by_helpers, 1u);
    EXPECT_EQ(metrics.help_items.value(), 1u);
    EXPECT_TRUE(loop.each_ran_once());
}

TEST(WorkerPool, stop_recalls_helpers_and_the_caller_finishes_the_loop) {
    auto pool = std::make_unique<WorkerPool>(2);
    Flag helping, stop_called;
    HelpedLoop loop(50, [&](std::size_t, unsigned slot) {
        if (slot == 0) {
            EXPECT_TRUE(helping.wait());  // the other worker took an item
        } else if (!helping.is_set()) {
            helping.set();
            EXPECT_TRUE(stop_called.wait());
        }
    });
    auto a = std::make_shared<BodyTask>([&] {
        loop.run(*pool, 1);
        EXPECT_TRUE(loop.each_ran_once());
    });
    pool->schedule(a);
    ASSERT_TRUE(helping.wait());
    std::thread stopper([&] { pool->stop(); });  // lets A's turn finish, joins the workers
    std::this_thread::sleep_for(1ms);            // most often inside stop() by then (not relied on)
    stop_called.set();
    stopper.join();
    // Whether the helper saw the recall after its first item or the caller had taken the rest:
    // stop() returned, the turn ended and every item ran once.
    EXPECT_TRUE(a->ran.is_set());
    EXPECT_TRUE(loop.each_ran_once());
}

}  // namespace
}  // namespace isomesh::server
