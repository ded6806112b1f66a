// Deadlines for work that cannot stop itself: a phase-1 polygonization (or a refinement step)
// that runs past the evaluation time limit gets its cancel flag raised by this thread.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <mutex>
#include <thread>

#include "server/clock.h"

namespace isomesh::server {

class Watchdog {
  public:
    Watchdog();
    ~Watchdog();
    Watchdog(const Watchdog&) = delete;
    Watchdog& operator=(const Watchdog&) = delete;

    /// While alive, raises `expired` then `cancel` once `deadline` passes.
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

    [[nodiscard]] Guard arm(Clock::time_point deadline, std::atomic<bool>& cancel,
                            std::atomic<bool>& expired);

  private:
    struct Alarm {
        Clock::time_point deadline;
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
