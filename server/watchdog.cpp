#include "server/watchdog.h"

namespace isomesh::server {

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

Watchdog::Guard Watchdog::arm(Clock::time_point deadline, std::atomic<bool>& cancel,
                              std::atomic<bool>& expired) {
    std::uint64_t token;
    {
        std::lock_guard lock(mutex_);
        token = next_token_++;
        alarms_[token] = {deadline, &cancel, &expired};
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
            if (it->second.deadline <= now) {
                it->second.expired->store(true);
                it->second.cancel->store(true);
                it = alarms_.erase(it);
            } else {
                earliest = std::min(earliest, it->second.deadline);
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
