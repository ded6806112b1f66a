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

/// The CPU time of one thread in microseconds (WorkBudget::thread_cpu_clock). Reading it is a
/// system call (a microsecond or so; the vDSO serves only the process-wide clocks); a budget on
/// it reads it only when wall time says its end may have come (WorkBudget::exhausted).
struct ThreadCpuClock {
    clockid_t id;
    std::int64_t operator()() const {
        timespec t{};
        clock_gettime(id, &t);
        return std::int64_t{t.tv_sec} * 1000000 + t.tv_nsec / 1000;
    }
};

class WorkBudget {
  public:
    /// Microseconds (or any unit the budget is given in), monotonic, thread-safe.
    using Clock = std::function<std::int64_t()>;

    /// Steady wall-clock time.
    static Clock wall_clock() { return wall_microseconds; }

    /// The CPU time of the calling thread (readable from any thread, so workers helping that
    /// thread charge its budget only through its own time).
    static Clock thread_cpu_clock() {
        clockid_t id{};
        if (pthread_getcpuclockid(pthread_self(), &id) != 0) return wall_clock();
        return ThreadCpuClock{id};
    }

    /// No limit at all.
    WorkBudget() = default;
    /// No time limit; cancelled only by `cancel` (may be null).
    explicit WorkBudget(const std::atomic<bool>* cancel) : cancel_(cancel) {}

    /// `limit` units of `clock` from now; `cancel` may be null.
    WorkBudget(std::int64_t limit, Clock clock, const std::atomic<bool>* cancel = nullptr)
        : cancel_(cancel), clock_(std::make_shared<Clock>(std::move(clock))) {
        if (clock_->target<ThreadCpuClock>() != nullptr) {
            const std::int64_t wall = wall_microseconds();
            start_ = (*clock_)();
            pace_ = std::make_shared<Pace>(wall, start_);
        } else {
            start_ = (*clock_)();
        }
        end_ = limit >= std::numeric_limits<std::int64_t>::max() - start_
                   ? std::numeric_limits<std::int64_t>::max()
                   : start_ + limit;
    }

    bool cancelled() const {
        return cancel_ != nullptr && cancel_->load(std::memory_order_relaxed);
    }
    bool timed() const { return clock_ != nullptr; }
    /// Time is up or the work is cancelled. Thread-safe.
    bool exhausted() const {
        if (cancelled()) return true;
        if (!clock_) return false;
        if (pace_ && pace_->upper_bound() < end_) return false;
        return read() >= end_;
    }
    /// Units used since the budget was made (0 without a clock).
    std::int64_t elapsed() const { return clock_ ? read() - start_ : 0; }
    /// Units left (the maximum without a clock; 0 once exhausted).
    std::int64_t remaining() const {
        if (!clock_) return std::numeric_limits<std::int64_t>::max();
        const std::int64_t now = read();
        return now >= end_ ? 0 : end_ - now;
    }
    /// A budget on the same clock and cancel flag ending when `fraction` of what is left now is
    /// used (never after this one ends).
    WorkBudget portion(double fraction) const {
        if (!clock_) return *this;
        WorkBudget part = *this;
        const std::int64_t now = read();
        const std::int64_t left = now >= end_ ? 0 : end_ - now;
        part.start_ = now;
        part.end_ = now + static_cast<std::int64_t>(fraction * static_cast<double>(left));
        return part;
    }
    const std::atomic<bool>* cancel_flag() const { return cancel_; }

  private:
    static std::int64_t wall_microseconds() {
        return std::chrono::duration_cast<std::chrono::microseconds>(
                   std::chrono::steady_clock::now().time_since_epoch())
            .count();
    }

    /// The last reading of a thread's CPU clock and the wall time just before it: the thread's
    /// CPU time runs no faster than wall time, so at wall time w it is at most
    /// cpu + (w - wall). Both as microseconds from the first reading, packed in one atomic word
    /// (32 bits each: an hour) so that threads sharing the budget see a consistent pair.
    struct Pace {
        Pace(std::int64_t wall, std::int64_t cpu) : wall_base(wall), cpu_base(cpu) {}
        const std::int64_t wall_base, cpu_base;  // the first reading
        std::atomic<std::uint64_t> last{0};      // the last, as (wall, cpu) from the first

        std::int64_t upper_bound() const {
            const std::uint64_t packed = last.load(std::memory_order_acquire);
            const auto wall = static_cast<std::int64_t>(packed >> 32);
            const auto cpu = static_cast<std::int64_t>(packed & 0xffffffffu);
            return cpu_base + cpu + (wall_microseconds() - wall_base - wall);
        }
        void record(std::int64_t wall, std::int64_t cpu) {
            const std::int64_t dw = wall - wall_base, dc = cpu - cpu_base;
            if (dw < 0 || dc < 0 || dw > 0xffffffffll || dc > 0xffffffffll) return;
            last.store((static_cast<std::uint64_t>(dw) << 32) | static_cast<std::uint64_t>(dc),
                       std::memory_order_release);
        }
    };

    /// The clock now (and, for a paced clock, the pair its bound starts from).
    std::int64_t read() const {
        if (!pace_) return (*clock_)();
        const std::int64_t wall = wall_microseconds();  // before the reading: see Pace
        const std::int64_t now = (*clock_)();
        pace_->record(wall, now);
        return now;
    }

    const std::atomic<bool>* cancel_ = nullptr;
    std::shared_ptr<Clock> clock_;
    std::shared_ptr<Pace> pace_;  // for a ThreadCpuClock
    std::int64_t start_ = 0;
    std::int64_t end_ = std::numeric_limits<std::int64_t>::max();
};

}  // namespace isomesh
