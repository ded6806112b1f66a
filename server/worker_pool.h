// The refinement worker pool: a fixed set of threads running tasks (sessions) in short turns,
// round-robin. A task that wants more time after its turn goes to the back of the queue, so a
// heavy model cannot starve a light one: with T tasks wanting work, each waits at most T - 1
// turns between two of its own. A task is never run by two threads at once.
//
// Three lanes: work a user of a running session is waiting for (a slider's new version, a
// keyframe for a late subscriber) is scheduled in the urgent lane and a new session's first mesh
// in the new-session lane; both are served before any round-robin turn, so their latency is one
// turn of the busiest worker rather than a whole round over every refining session. While both
// have work they share the workers' time equally (the CPU time of their turns since both had work,
// the lane with less going next), so that a burst of new sessions cannot hold up the running
// sessions' updates, nor dragged sliders the first meshes: taking turns one for one, a slider's
// update of 2 ms held up each cached first mesh of 0.15 ms (bench/load/run.sh, 1,000 sessions of
// the light mix: new sessions waited up to 400 ms behind 190 urgent turns). Continuation turns
// always go to the round-robin lane.
//
// A task may also ask for a turn at a later time (schedule_at): a session waiting for a dragged
// slider to rest. Until then it costs nothing; its turn then goes to the round-robin lane.
//
// The pool is also an executor of help offers (work/helpers.h): a running task's parallel loop (a
// session's phase 1) offers its items to the other workers, which take the offer only when no
// task is queued in any lane and no timer is due, and go back to the tasks after the item they
// run once one is (recall): help is the lowest priority, a busy server gives each session one
// core as without it, and a queued task waits at most one help item longer.
#pragma once

#include <array>
#include <atomic>
#include <condition_variable>
#include <deque>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <thread>
#include <utility>
#include <vector>

#include "server/clock.h"
#include "server/metrics.h"
#include "work/helpers.h"

namespace isomesh::server {

enum class Lane { round_robin, urgent, new_session };

class Task {
  public:
    virtual ~Task() = default;
    /// One turn: a bounded amount of work (a time slice). Returns true to get another turn.
    virtual bool run_slice() = 0;

  private:
    friend class WorkerPool;
    enum class State { idle, queued, running, running_rescheduled };
    State state_ = State::idle;  // guarded by the pool's mutex
    /// The lane it is queued in, or to be requeued in; same guard.
    Lane lane_ = Lane::round_robin;
    std::optional<Clock::time_point> wake_at_;  // its entry in the pool's timers; same guard
};

class WorkerPool final : public Helpers {
  public:
    using ErrorHandler = std::function<void(std::exception_ptr)>;

    /// Starts `threads` (>= 1) workers. `metrics` (optional) receives run_queue and busy_workers;
    /// `on_error` is told of any exception escaping a turn (the task then counts as idle). The
    /// workers run `nice` levels below the thread that starts them (Linux's nice value, capped at
    /// 19): the network threads, which accept connections, read requests and write frames in
    /// moments, come first when the cores are full of refinement.
    explicit WorkerPool(unsigned threads, Metrics* metrics = nullptr, ErrorHandler on_error = {},
                        int nice = 0);
    ~WorkerPool() override;
    WorkerPool(const WorkerPool&) = delete;
    WorkerPool& operator=(const WorkerPool&) = delete;

    /// Gives `task` a turn soon: queues it in `lane` when idle; when it is running, it gets another
    /// turn (in `lane`) after the current one; when queued in the round-robin lane, it moves to
    /// `lane`, and otherwise stays. Thread-safe; ignored after stop().
    void schedule(const std::shared_ptr<Task>& task, Lane lane = Lane::round_robin);
    /// Gives `task` a round-robin turn at `when` (as schedule() then), replacing a turn it asked
    /// for this way before. Thread-safe; ignored after stop().
    void schedule_at(const std::shared_ptr<Task>& task, Clock::time_point when);

    /// Helpers: offers `offer` to up to `threads` workers, taken when idle (see above); ignored
    /// after stop(). Thread-safe.
    void offer(const std::shared_ptr<HelpOffer>& offer, unsigned threads) override;
    void withdraw(const HelpOffer& offer) override;
    /// As offer(), the CPU time the helpers spend on it added to `*cpu` (a session's account).
    void offer_charged(const std::shared_ptr<HelpOffer>& offer, unsigned threads,
                       std::shared_ptr<std::atomic<Clock::rep>> cpu);

    /// Waits until no task is queued, running or due later and no worker helps, or until
    /// `deadline`; true when idle.
    bool wait_idle(Clock::time_point deadline);

    /// Lets running turns finish, drops queued tasks and joins the threads. Idempotent.
    void stop();

    unsigned thread_count() const { return static_cast<unsigned>(threads_.size()); }
    std::size_t queued() const;

  private:
    void work();
    /// An offer with the threads it may still have and the account its helpers' CPU time goes to.
    struct OfferEntry {
        std::shared_ptr<HelpOffer> offer;
        unsigned threads;
        std::shared_ptr<std::atomic<Clock::rep>> cpu;  // may be null
    };
    /// Runs help it took (the mutex not held), counting its items and charging its CPU time.
    void help(const OfferEntry& entry);
    /// A helper's recall: a task is queued, a timer is due or the pool is stopping.
    bool wanted_back() const;
    /// With the mutex held: the first offer, one thread fewer for it.
    std::optional<OfferEntry> take_offer();
    /// With the mutex held, after timers_ changed: keeps next_timer_ in step.
    void note_timers();
    /// With the mutex held and a task queued; `lane` receives the lane it came from.
    std::shared_ptr<Task> next_task(Lane& lane);
    void enqueue(const std::shared_ptr<Task>& task);  // in the lane of task->lane_
    /// From the round-robin lane to `lane`.
    void promote(const std::shared_ptr<Task>& task, Lane lane);
    std::deque<std::shared_ptr<Task>>& queue_of(Lane lane);
    /// `lane`: where the turn came from; `cpu`: the CPU time it took.
    void finish_turn(const std::shared_ptr<Task>& task, bool wants_more, Lane lane,
                     Clock::duration cpu);
    void schedule_locked(const std::shared_ptr<Task>& task, Lane lane);
    /// Queues the tasks whose time has come; returns when the next one is due.
    std::optional<Clock::time_point> release_due(Clock::time_point now);
    bool nothing_queued() const {
        return urgent_.empty() && new_sessions_.empty() && queue_.empty();
    }
    bool idle() const {
        return nothing_queued() && running_ == 0 && helping_ == 0 && timers_.empty();
    }

    mutable std::mutex mutex_;
    std::condition_variable wake_;
    std::condition_variable idle_;
    std::size_t running_ = 0;
    std::size_t helping_ = 0;  // workers in help()
    std::deque<std::shared_ptr<Task>> urgent_;
    std::deque<std::shared_ptr<Task>> new_sessions_;
    /// The CPU time of the urgent and new-session lanes' turns (by Lane) since both had work: the
    /// lane with less goes next while both have work; reset when either runs out.
    std::array<Clock::duration, 3> lane_time_{};
    std::deque<std::shared_ptr<Task>> queue_;                               // the round-robin lane
    std::set<std::pair<Clock::time_point, std::shared_ptr<Task>>> timers_;  // schedule_at
    bool stopping_ = false;
    /// Help offers with the threads they may still have, oldest first.
    std::deque<OfferEntry> offers_;
    // Read by helpers without the mutex (wanted_back); written with it.
    std::atomic<std::size_t> queued_tasks_ = 0;  // in the three lanes
    std::atomic<Clock::rep> next_timer_;         // the first of timers_ (the maximum if none)
    std::atomic<bool> recall_all_ = false;       // stopping
    Metrics* metrics_;
    ErrorHandler on_error_;
    std::vector<std::thread> threads_;
};

/// A task's door to the pool's help (a session's phase 1: session.h): offers go to the pool, and
/// the CPU time its helpers spend is counted for the task to charge to itself (cpu()).
class ChargedHelpers final : public Helpers {
  public:
    explicit ChargedHelpers(WorkerPool& pool) : pool_(pool) {}
    void offer(const std::shared_ptr<HelpOffer>& offer, unsigned threads) override {
        pool_.offer_charged(offer, threads, cpu_);
    }
    void withdraw(const HelpOffer& offer) override { pool_.withdraw(offer); }
    /// The CPU time the helpers spent so far (a helper adds its time once it leaves the offer).
    Clock::duration cpu() const { return Clock::duration(cpu_->load()); }
    unsigned threads() const { return pool_.thread_count(); }

  private:
    WorkerPool& pool_;
    // Shared: a helper adds its time after help() returned, when the task may be gone.
    std::shared_ptr<std::atomic<Clock::rep>> cpu_ = std::make_shared<std::atomic<Clock::rep>>(0);
};

}  // namespace isomesh::server
