// CPU-time limits for work that cannot stop itself: a phase-1 polygonization (or a refinement
// step) whose thread uses more CPU time than allowed gets its cancel flag raised by this thread.
// The limits count the CPU time of the working thread itself, not the wall clock, so work slowed
// down by a busy machine is not cut short. The watchdog sleeps until the earliest moment an alarm
// could be due (a thread cannot use CPU time faster than the clock runs), then looks again.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <mutex>
#include <thread>

#include <time.h>

#include "server/clock.h"

namespace isomesh::server {

class Watchdog {
  public:
    Watchdog();
    ~Watchdog();
    Watchdog(const Watchdog&) = delete;
    Watchdog& operator=(const Watchdog&) = delete;

    /// While alive, raises `expired` then `cancel` once the calling thread has used `cpu_time`
    /// more CPU time than it had when arm() was called.
    class Guard {
      public:
        Guard(Guard&& other) noexcept : owner_(other.owner_), token_(other.token_) {
            other.owner_ = nullptr;
        }
        Guard(const Guard&) = delete;
        Guard& operator=(const Guard&) = delete;
        Guard& operator=(Guard&&) = delete;
        /// Disarms: after it returns the flags are not touched any more.
        ~Guard();

      private:
        friend class Watchdog;
        Guard(Watchdog* owner, std::uint64_t token) : owner_(owner), token_(token) {}
        Watchdog* owner_;
        std::uint64_t token_;
    };

    [[nodiscard]] Guard arm(Clock::duration cpu_time, std::atomic<bool>& cancel,
                            std::atomic<bool>& expired);

  private:
    struct Alarm {
        clockid_t clock;               // the armed thread's CPU clock
        Clock::duration cpu_deadline;  // on that clock
        std::atomic<bool>* cancel;
        std::atomic<bool>* expired;
    };
    void disarm(std::uint64_t token);
    void run();

    std::mutex mutex_;
    std::condition_variable changed_;
    std::map<std::uint64_t, Alarm> alarms_;
    std::uint64_t next_token_ = 0;
    bool stopping_ = false;
    std::thread thread_;
};

}  // namespace isomesh::server
