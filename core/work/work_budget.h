// Work budgets: how long a computation may run before it returns what it has, and the flag that
// cancels it. Every long loop in core (the octree, the mesh build, the simplifier, the refiner)
// checks one between items, so that a time slice ends on time and a new version, a close or a
// shutdown stops the work within one item (libfive's and Fidget's "one settings struct with
// cancellation per render").
//
// Time is read from a clock the caller chooses: wall time, the CPU time of one thread (a server's
// worker: its slices are CPU time, so a busy machine does not shorten them), or any monotonic
// counter (tests count evaluations instead of microseconds, so they never depend on speed).
#pragma once

#include <pthread.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <ctime>
#include <functional>
#include <limits>
#include <memory>

namespace isomesh {

class WorkBudget {
  public:
    /// Microseconds (or any unit the budget is given in), monotonic, thread-safe.
    using Clock = std::function<std::int64_t()>;

    /// Steady wall-clock time.
    static Clock wall_clock() {
        return [] {
            return std::chrono::duration_cast<std::chrono::microseconds>(
                       std::chrono::steady_clock::now().time_since_epoch())
                .count();
        };
    }

    /// The CPU time of the calling thread (readable from any thread, so workers helping that
    /// thread charge its budget only through its own time).
    static Clock thread_cpu_clock() {
        clockid_t id{};
        if (pthread_getcpuclockid(pthread_self(), &id) != 0) return wall_clock();
        return [id] {
            timespec t{};
            clock_gettime(id, &t);
            return std::int64_t{t.tv_sec} * 1000000 + t.tv_nsec / 1000;
        };
    }

    /// No limit at all.
    WorkBudget() = default;
    /// No time limit; cancelled only by `cancel` (may be null).
    explicit WorkBudget(const std::atomic<bool>* cancel) : cancel_(cancel) {}

    /// `limit` units of `clock` from now; `cancel` may be null.
    WorkBudget(std::int64_t limit, Clock clock, const std::atomic<bool>* cancel = nullptr)
        : cancel_(cancel), clock_(std::make_shared<Clock>(std::move(clock))) {
        start_ = (*clock_)();
        end_ = limit >= std::numeric_limits<std::int64_t>::max() - start_
                   ? std::numeric_limits<std::int64_t>::max()
                   : start_ + limit;
    }

    bool cancelled() const {
        return cancel_ != nullptr && cancel_->load(std::memory_order_relaxed);
    }
    bool timed() const { return clock_ != nullptr; }
    /// Time is up or the work is cancelled. Thread-safe.
    bool exhausted() const { return cancelled() || (clock_ && (*clock_)() >= end_); }
    /// Units used since the budget was made (0 without a clock).
    std::int64_t elapsed() const { return clock_ ? (*clock_)() - start_ : 0; }
    /// Units left (the maximum without a clock; 0 once exhausted).
    std::int64_t remaining() const {
        if (!clock_) return std::numeric_limits<std::int64_t>::max();
        const std::int64_t now = (*clock_)();
        return now >= end_ ? 0 : end_ - now;
    }
    /// A budget on the same clock and cancel flag ending when `fraction` of what is left now is
    /// used (never after this one ends).
    WorkBudget portion(double fraction) const {
        if (!clock_) return *this;
        WorkBudget part = *this;
        const std::int64_t now = (*clock_)();
        const std::int64_t left = now >= end_ ? 0 : end_ - now;
        part.start_ = now;
        part.end_ = now + static_cast<std::int64_t>(fraction * static_cast<double>(left));
        return part;
    }
    const std::atomic<bool>* cancel_flag() const { return cancel_; }

  private:
    const std::atomic<bool>* cancel_ = nullptr;
    std::shared_ptr<Clock> clock_;
    std::int64_t start_ = 0;
    std::int64_t end_ = std::numeric_limits<std::int64_t>::max();
};

}  // namespace isomesh
