#include "server/worker_pool.h"

#include "server/resources.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <future>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <sys/resource.h>

namespace isomesh::server {
namespace {

using namespace std::chrono_literals;

/// A task that wants `turns` turns, each spending `turn_time` of its thread's CPU time (what the
/// pool shares), and records when it ran.
class CountingTask : public Task {
  public:
    CountingTask(int turns, Clock::duration turn_time, std::vector<char>* log, char name,
                 std::mutex* log_mutex)
        : turns_left(turns), turn_time_(turn_time), log_(log), name_(name), log_mutex_(log_mutex) {}

    bool run_slice() override {
        const int concurrent = running_.fetch_add(1) + 1;
        max_concurrent = std::max(max_concurrent.load(), concurrent);
        const auto end = thread_cpu_time() + turn_time_;
        while (thread_cpu_time() < end) {
        }
        if (log_) {
            std::lock_guard lock(*log_mutex_);
            log_->push_back(name_);
        }
        ++turns_run;
        running_.fetch_sub(1);
        return --turns_left > 0;
    }

    std::atomic<int> turns_left;
    std::atomic<int> turns_run{0};
    std::atomic<int> max_concurrent{0};

  private:
    std::atomic<int> running_{0};
    Clock::duration turn_time_;
    std::vector<char>* log_;
    char name_;
    std::mutex* log_mutex_;
};

bool wait_for(const std::function<bool()>& done, Clock::duration limit = 10s) {
    const auto end = Clock::now() + limit;
    while (!done()) {
        if (Clock::now() > end) return false;
        std::this_thread::sleep_for(1ms);
    }
    return true;
}

TEST(WorkerPool, light_task_is_not_starved_by_a_heavy_one) {
    std::vector<char> log;
    std::mutex log_mutex;
    WorkerPool pool(1);
    auto heavy = std::make_shared<CountingTask>(1000, 1ms, &log, 'H', &log_mutex);
    auto light = std::make_shared<CountingTask>(3, 1ms, &log, 'L', &log_mutex);
    pool.schedule(heavy);
    std::this_thread::sleep_for(5ms);
    pool.schedule(light);
    ASSERT_TRUE(wait_for([&] { return light->turns_left == 0; }));
    pool.stop();
    // Round-robin: between two turns of the light task the heavy one gets exactly one.
    std::vector<std::size_t> light_turns;
    for (std::size_t i = 0; i < log.size(); ++i)
        if (log[i] == 'L') light_turns.push_back(i);
    ASSERT_EQ(light_turns.size(), 3u);
    EXPECT_EQ(light_turns[1] - light_turns[0], 2u);
    EXPECT_EQ(light_turns[2] - light_turns[1], 2u);
    EXPECT_GT(heavy->turns_left, 0);  // the heavy task was still going
}

TEST(WorkerPool, task_never_runs_on_two_threads_and_reruns_when_scheduled_while_running) {
    /// Its first turn waits until the test has scheduled it again many times.
    struct GatedTask : Task {
        bool run_slice() override {
            const int concurrent = ++running;
            max_concurrent = std::max(max_concurrent.load(), concurrent);
            if (turns++ == 0) {
                started.set_value();
                release.get_future().wait();
            }
            --running;
            return false;
        }
        std::atomic<int> running{0}, max_concurrent{0}, turns{0};
        std::promise<void> started, release;
    };
    WorkerPool pool(4);
    auto task = std::make_shared<GatedTask>();
    pool.schedule(task);
    task->started.get_future().wait();
    for (int i = 0; i < 50; ++i) pool.schedule(task);
    task->release.set_value();
    ASSERT_TRUE(pool.wait_idle(Clock::now() + 10s));
    EXPECT_EQ(task->max_concurrent.load(), 1);
    EXPECT_EQ(task->turns.load(), 2);  // the schedules while it ran collapse into one turn
}

/// A one-thread pool whose worker is held by a task until release(): what the test schedules
/// meanwhile queues, and then runs in queue order, logging its name.
class HeldPool {
  public:
    HeldPool() {
        pool.schedule(blocker_);
        blocker_->started.get_future().wait();
    }
    /// A task of `turns` turns, each spending `turn_time` of CPU time.
    std::shared_ptr<CountingTask> task(int turns, char name, Clock::duration turn_time = 0ms) {
        return std::make_shared<CountingTask>(turns, turn_time, &log_, name, &log_mutex_);
    }
    /// Lets the queued tasks run; returns the names of their turns in order.
    std::string release() {
        blocker_->release.set_value();
        EXPECT_TRUE(pool.wait_idle(Clock::now() + 10s));
        return std::string(log_.begin(), log_.end());
    }

    WorkerPool pool{1};

  private:
    struct BlockingTask : Task {
        bool run_slice() override {
            started.set_value();
            release.get_future().wait();
            return false;
        }
        std::promise<void> started, release;
    };
    std::shared_ptr<BlockingTask> blocker_ = std::make_shared<BlockingTask>();
    std::vector<char> log_;
    std::mutex log_mutex_;
};

TEST(WorkerPool, schedule_urgent_runs_before_round_robin_turns) {
    HeldPool held;
    held.pool.schedule(held.task(2, 'a'));
    held.pool.schedule(held.task(1, 'b'));
    held.pool.schedule(held.task(2, 'U'), Lane::urgent);
    // U's first turn jumps the queue; its continuation waits its round-robin turn after a and b.
    EXPECT_EQ(held.release(), "UabUa");
}

TEST(WorkerPool, schedule_urgent_promotes_a_queued_task) {
    HeldPool held;
    auto b = held.task(1, 'b');
    held.pool.schedule(held.task(1, 'a'));
    held.pool.schedule(b);
    held.pool.schedule(b, Lane::urgent);
    held.pool.schedule(b, Lane::urgent);  // already urgent: stays queued once
    EXPECT_EQ(held.pool.queued(), 2u);
    EXPECT_EQ(held.release(), "ba");
}

TEST(WorkerPool, schedule_new_sessions_share_the_time_with_urgent_work) {
    HeldPool held;
    held.pool.schedule(held.task(1, 'r'));
    for (char name : {'a', 'b', 'c', 'd'})
        held.pool.schedule(held.task(1, name), Lane::new_session);
    // Urgent turns of 20 ms of CPU time each; the new sessions' take next to none.
    for (char name : {'U', 'V', 'W'}) held.pool.schedule(held.task(1, name, 20ms), Lane::urgent);
    // Neither lane holds the other up: after an urgent turn, the new sessions have the time it
    // took, enough for all four here; round-robin turns come after both.
    EXPECT_EQ(held.release(), "UabcdVWr");
}

TEST(WorkerPool, schedule_urgent_work_shares_the_time_with_long_new_sessions) {
    HeldPool held;
    for (char name : {'a', 'b', 'c'})
        held.pool.schedule(held.task(1, name, 20ms), Lane::new_session);
    for (char name : {'U', 'V', 'W', 'X'}) held.pool.schedule(held.task(1, name), Lane::urgent);
    // The other way round: a new session's long first step leaves the time for the urgent turns.
    EXPECT_EQ(held.release(), "UaVWXbc");
}

TEST(WorkerPool, schedule_new_session_promotes_a_queued_task_but_not_an_urgent_one) {
    HeldPool held;
    auto a = held.task(1, 'a');
    auto u = held.task(1, 'U');
    held.pool.schedule(held.task(1, 'r'));
    held.pool.schedule(a);
    held.pool.schedule(a, Lane::new_session);
    held.pool.schedule(u, Lane::urgent);
    held.pool.schedule(u, Lane::new_session);  // stays urgent
    EXPECT_EQ(held.pool.queued(), 3u);
    EXPECT_EQ(held.release(), "Uar");
}

TEST(WorkerPool, workers_run_nice_levels_below_the_thread_that_starts_them) {
    errno = 0;
    const int own = getpriority(PRIO_PROCESS, 0);  // this thread's (Linux: per thread)
    ASSERT_EQ(errno, 0);
    std::atomic<int> seen{-100};
    struct NiceTask : Task {
        explicit NiceTask(std::atomic<int>& seen) : seen(seen) {}
        bool run_slice() override {
            seen = getpriority(PRIO_PROCESS, 0);
            return false;
        }
        std::atomic<int>& seen;
    };
    WorkerPool pool(1, nullptr, {}, 3);
    pool.schedule(std::make_shared<NiceTask>(seen));
    ASSERT_TRUE(pool.wait_idle(Clock::now() + 10s));
    EXPECT_EQ(seen.load(), std::min(own + 3, 19));
    EXPECT_EQ(getpriority(PRIO_PROCESS, 0), own);  // the starting thread keeps its own
}

TEST(WorkerPool, stop_drops_queued_work_and_joins) {
    auto pool = std::make_unique<WorkerPool>(2);
    std::vector<std::shared_ptr<CountingTask>> tasks;
    for (int i = 0; i < 8; ++i) {
        tasks.push_back(std::make_shared<CountingTask>(1'000'000, 1ms, nullptr, 'x', nullptr));
        pool->schedule(tasks.back());
    }
    std::this_thread::sleep_for(20ms);
    const auto start = Clock::now();
    pool->stop();
    EXPECT_LT(Clock::now() - start, 5s);  // turns are 1 ms: stop does not wait for the queue
    std::vector<int> runs;
    for (auto& t : tasks) runs.push_back(t->turns_run);
    std::this_thread::sleep_for(10ms);
    for (std::size_t i = 0; i < tasks.size(); ++i) EXPECT_EQ(tasks[i]->turns_run, runs[i]);
    pool->schedule(tasks[0]);  // ignored after stop
    EXPECT_EQ(pool->queued(), 0u);
}

TEST(WorkerPool, exceptions_are_reported_and_the_pool_keeps_working) {
    struct Throwing : Task {
        bool run_slice() override { throw std::runtime_error("boom"); }
    };
    std::atomic<int> errors{0};
    WorkerPool pool(1, nullptr, [&](std::exception_ptr) { ++errors; });
    pool.schedule(std::make_shared<Throwing>());
    auto task = std::make_shared<CountingTask>(2, 0ms, nullptr, 'T', nullptr);
    pool.schedule(task);
    ASSERT_TRUE(pool.wait_idle(Clock::now() + 10s));
    EXPECT_EQ(errors.load(), 1);
    EXPECT_EQ(task->turns_run.load(), 2);
}

/// A task that records when its turns ran.
struct TimedTask : Task {
    bool run_slice() override {
        std::lock_guard lock(mutex);
        turns.push_back(Clock::now());
        return false;
    }
    std::mutex mutex;
    std::vector<Clock::time_point> turns;
};

TEST(WorkerPool, schedule_at_gives_one_turn_once_its_time_has_come) {
    WorkerPool pool(2);
    auto task = std::make_shared<TimedTask>();
    const Clock::time_point when = Clock::now() + 30ms;
    pool.schedule_at(task, when);
    pool.schedule_at(task, when + 20ms);  // replaces the first
    // A turn booked for later counts as work: idle only once it ran.
    ASSERT_TRUE(pool.wait_idle(Clock::now() + 10s));
    std::lock_guard lock(task->mutex);
    ASSERT_EQ(task->turns.size(), 1u);
    EXPECT_GE(task->turns[0], when + 20ms);
}

TEST(WorkerPool, stop_drops_turns_booked_for_later) {
    auto task = std::make_shared<TimedTask>();
    {
        WorkerPool pool(1);
        pool.schedule_at(task, Clock::now() + 1h);
        pool.stop();
        EXPECT_TRUE(pool.wait_idle(Clock::now()));
    }
    EXPECT_TRUE(task->turns.empty());
    EXPECT_EQ(task.use_count(), 1);  // the pool let go of it
}

TEST(WorkerPool, metrics_count_queue_and_busy_workers) {
    Metrics metrics;
    {
        WorkerPool pool(2, &metrics);
        EXPECT_EQ(metrics.worker_threads.value(), 2);
        auto task = std::make_shared<CountingTask>(5, 1ms, nullptr, 'T', nullptr);
        pool.schedule(task);
        ASSERT_TRUE(pool.wait_idle(Clock::now() + 10s));
    }
    EXPECT_EQ(metrics.run_queue.value(), 0);
    EXPECT_EQ(metrics.busy_workers.value(), 0);
}

}  // namespace
}  // namespace isomesh::server
