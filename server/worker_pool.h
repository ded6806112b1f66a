// The refinement worker pool: a fixed set of threads running tasks (sessions) in short turns,
// round-robin. A task that wants more time after its turn goes to the back of the queue, so a
// heavy model cannot starve a light one: with T tasks wanting work, each waits at most T - 1
// turns between two of its own. A task is never run by two threads at once.
#pragma once

#include <condition_variable>
#include <deque>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "server/clock.h"
#include "server/metrics.h"

namespace isomesh::server {

class Task {
  public:
    virtual ~Task() = default;
    /// One turn: a bounded amount of work (a time slice). Returns true to get another turn.
    virtual bool run_slice() = 0;

  private:
    friend class WorkerPool;
    enum class State { idle, queued, running, running_rescheduled };
    State state_ = State::idle;  // guarded by the pool's mutex
};

class WorkerPool {
  public:
    using ErrorHandler = std::function<void(std::exception_ptr)>;

    /// Starts `threads` (>= 1) workers. `metrics` (optional) receives run_queue and busy_workers;
    /// `on_error` is told of any exception escaping a turn (the task then counts as idle).
    explicit WorkerPool(unsigned threads, Metrics* metrics = nullptr, ErrorHandler on_error = {});
    ~WorkerPool();
    WorkerPool(const WorkerPool&) = delete;
    WorkerPool& operator=(const WorkerPool&) = delete;

    /// Gives `task` a turn soon: queues it when idle; when it is running, it gets another turn
    /// after the current one; when queued, does nothing. Thread-safe; ignored after stop().
    void schedule(const std::shared_ptr<Task>& task);

    /// Waits until no task is queued or running, or until `deadline`; true when idle.
    bool wait_idle(Clock::time_point deadline);

    /// Lets running turns finish, drops queued tasks and joins the threads. Idempotent.
    void stop();

    unsigned thread_count() const { return static_cast<unsigned>(threads_.size()); }
    std::size_t queued() const;

  private:
    void work();
    void finish_turn(const std::shared_ptr<Task>& task, bool wants_more);

    mutable std::mutex mutex_;
    std::condition_variable wake_;
    std::condition_variable idle_;
    std::size_t running_ = 0;
    std::deque<std::shared_ptr<Task>> queue_;
    bool stopping_ = false;
    Metrics* metrics_;
    ErrorHandler on_error_;
    std::vector<std::thread> threads_;
};

}  // namespace isomesh::server
