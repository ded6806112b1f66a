#include "server/watchdog.h"

#include <pthread.h>

namespace isomesh::server {
namespace {

Clock::duration cpu_time_of(clockid_t clock) {
    timespec t{};
    if (clock_gettime(clock, &t) != 0) return Clock::duration::max();  // the thread is gone
    return std::chrono::duration_cast<Clock::duration>(std::chrono::seconds(t.tv_sec) +
                                                       std::chrono::nanoseconds(t.tv_nsec));
}

}  // namespace

Watchdog::Watchdog() : thread_([this] { run(); }) {}

Watchdog::~Watchdog() {
    {
        std::lock_guard lock(mutex_);
        stopping_ = true;
    }
    changed_.notify_all();
    thread_.join();
}

Watchdog::Guard::~Guard() {
    if (owner_) owner_->disarm(token_);
}

Watchdog::Guard Watchdog::arm(Clock::duration cpu_time, std::atomic<bool>& cancel,
                              std::atomic<bool>& expired) {
    clockid_t clock{};
    pthread_getcpuclockid(pthread_self(), &clock);
    const Clock::duration deadline = cpu_time_of(clock) + cpu_time;
    std::uint64_t token;
    {
        std::lock_guard lock(mutex_);
        token = next_token_++;
        alarms_[token] = {clock, deadline, &cancel, &expired};
    }
    changed_.notify_all();
    return Guard(this, token);
}

void Watchdog::disarm(std::uint64_t token) {
    std::lock_guard lock(mutex_);  // the flags are only written under this lock
    alarms_.erase(token);
}

void Watchdog::run() {
    std::unique_lock lock(mutex_);
    while (!stopping_) {
        const Clock::time_point now = Clock::now();
        Clock::time_point earliest = Clock::time_point::max();
        for (auto it = alarms_.begin(); it != alarms_.end();) {
            const Clock::duration used = cpu_time_of(it->second.clock);
            if (used >= it->second.cpu_deadline) {
                it->second.expired->store(true);
                it->second.cancel->store(true);
                it = alarms_.erase(it);
            } else {
                // The thread cannot use the rest of its CPU time before this moment.
                earliest = std::min(earliest, now + (it->second.cpu_deadline - used));
                ++it;
            }
        }
        if (earliest == Clock::time_point::max()) {
            changed_.wait(lock);
        } else {
            changed_.wait_until(lock, earliest);
        }
    }
}

}  // namespace isomesh::server
