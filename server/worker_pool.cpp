#include "server/worker_pool.h"

#include <algorithm>
#include <cassert>
#include <cerrno>

#include <sys/resource.h>

#include "server/resources.h"

namespace isomesh::server {

namespace {

/// Lowers the calling thread's scheduling priority by `levels` (on Linux, PRIO_PROCESS with id 0
/// names the calling thread, not the whole process). Lowering needs no privilege; a failure
/// leaves the priority as it was.
void lower_priority(int levels) {
    if (levels <= 0) return;
    errno = 0;
    const int now = getpriority(PRIO_PROCESS, 0);
    if (errno != 0) return;
    setpriority(PRIO_PROCESS, 0, std::min(now + levels, 19));
}

}  // namespace

WorkerPool::WorkerPool(unsigned threads, Metrics* metrics, ErrorHandler on_error, int nice)
    : next_timer_(Clock::time_point::max().time_since_epoch().count()),
      metrics_(metrics),
      on_error_(std::move(on_error)) {
    assert(threads >= 1);
    if (metrics_) metrics_->worker_threads.set(threads);
    for (unsigned i = 0; i < threads; ++i) {
        threads_.emplace_back([this, nice] {
            lower_priority(nice);
            work();
        });
    }
}

WorkerPool::~WorkerPool() {
    stop();
}

void WorkerPool::schedule(const std::shared_ptr<Task>& task, Lane lane) {
    std::lock_guard lock(mutex_);
    if (stopping_) return;
    schedule_locked(task, lane);
}

void WorkerPool::schedule_at(const std::shared_ptr<Task>& task, Clock::time_point when) {
    std::lock_guard lock(mutex_);
    if (stopping_) return;
    if (task->wake_at_) timers_.erase({*task->wake_at_, task});
    task->wake_at_ = when;
    timers_.emplace(when, task);
    note_timers();
    wake_.notify_one();  // a worker waiting for a later timer waits for this one instead
}

std::optional<Clock::time_point> WorkerPool::release_due(Clock::time_point now) {
    while (!timers_.empty() && timers_.begin()->first <= now) {
        std::shared_ptr<Task> task = timers_.begin()->second;
        timers_.erase(timers_.begin());
        task->wake_at_.reset();
        schedule_locked(task, Lane::round_robin);
    }
    note_timers();
    if (timers_.empty()) return std::nullopt;
    return timers_.begin()->first;
}

void WorkerPool::schedule_locked(const std::shared_ptr<Task>& task, Lane lane) {
    switch (task->state_) {
        case Task::State::idle:
            task->lane_ = lane;
            enqueue(task);
            break;
        case Task::State::running:
            task->state_ = Task::State::running_rescheduled;
            task->lane_ = lane;
            break;
        case Task::State::queued:
            if (lane != Lane::round_robin && task->lane_ == Lane::round_robin) promote(task, lane);
            break;
        case Task::State::running_rescheduled:
            if (task->lane_ == Lane::round_robin) task->lane_ = lane;
            break;
    }
}

std::deque<std::shared_ptr<Task>>& WorkerPool::queue_of(Lane lane) {
    switch (lane) {
        case Lane::urgent:
            return urgent_;
        case Lane::new_session:
            return new_sessions_;
        case Lane::round_robin:
            break;
    }
    return queue_;
}

void WorkerPool::note_timers() {
    next_timer_ = (timers_.empty() ? Clock::time_point::max() : timers_.begin()->first)
                      .time_since_epoch()
                      .count();
}

void WorkerPool::enqueue(const std::shared_ptr<Task>& task) {
    task->state_ = Task::State::queued;
    queue_of(task->lane_).push_back(task);
    ++queued_tasks_;
    if (metrics_) metrics_->run_queue.add(1);
    wake_.notify_one();
}

void WorkerPool::promote(const std::shared_ptr<Task>& task, Lane lane) {
    const auto it = std::find(queue_.begin(), queue_.end(), task);
    assert(it != queue_.end());
    queue_.erase(it);
    task->lane_ = lane;
    queue_of(lane).push_back(task);
}

std::shared_ptr<Task> WorkerPool::next_task(Lane& lane) {
    const std::size_t urgent = static_cast<std::size_t>(Lane::urgent);
    const std::size_t fresh = static_cast<std::size_t>(Lane::new_session);
    if (!urgent_.empty() && !new_sessions_.empty()) {
        // Both wait on a user: they share the time (worker_pool.h).
        lane = lane_time_[fresh] < lane_time_[urgent] ? Lane::new_session : Lane::urgent;
    } else {
        lane_time_ = {};
        lane = !urgent_.empty()         ? Lane::urgent
               : !new_sessions_.empty() ? Lane::new_session
                                        : Lane::round_robin;
    }
    auto& queue = queue_of(lane);
    std::shared_ptr<Task> task = std::move(queue.front());
    queue.pop_front();
    --queued_tasks_;
    return task;
}

void WorkerPool::stop() {
    {
        std::lock_guard lock(mutex_);
        if (stopping_ && threads_.empty()) return;
        stopping_ = true;
        recall_all_ = true;
        offers_.clear();
        for (auto* lane : {&urgent_, &new_sessions_, &queue_}) {
            if (metrics_) metrics_->run_queue.add(-static_cast<std::int64_t>(lane->size()));
            for (auto& task : *lane) task->state_ = Task::State::idle;
            lane->clear();
        }
        for (const auto& [when, task] : timers_) task->wake_at_.reset();
        timers_.clear();
        note_timers();
        queued_tasks_ = 0;
    }
    wake_.notify_all();
    for (std::thread& thread : threads_) thread.join();
    threads_.clear();
}

bool WorkerPool::wait_idle(Clock::time_point deadline) {
    std::unique_lock lock(mutex_);
    return idle_.wait_until(lock, deadline, [this] { return idle(); });
}

std::size_t WorkerPool::queued() const {
    std::lock_guard lock(mutex_);
    return urgent_.size() + new_sessions_.size() + queue_.size();
}

void WorkerPool::work() {
    for (;;) {
        std::shared_ptr<Task> task;
        std::optional<OfferEntry> help_offer;
        Lane lane = Lane::round_robin;
        {
            std::unique_lock lock(mutex_);
            for (;;) {
                const std::optional<Clock::time_point> next = release_due(Clock::now());
                if (stopping_ || !nothing_queued() || !offers_.empty()) break;
                if (next) {
                    wake_.wait_until(lock, *next);
                } else {
                    wake_.wait(lock);
                }
            }
            if (stopping_) return;
            if (nothing_queued()) help_offer = take_offer();  // help: only when no task waits
            if (help_offer) {
                ++helping_;
            } else {
                task = next_task(lane);
                task->state_ = Task::State::running;
                ++running_;
                if (metrics_) metrics_->run_queue.add(-1), metrics_->busy_workers.add(1);
            }
        }
        if (help_offer) {
            help(*help_offer);
            continue;
        }
        bool wants_more = false;
        const Clock::duration cpu_start = thread_cpu_time();
        try {
            wants_more = task->run_slice();
        } catch (...) {
            if (on_error_) on_error_(std::current_exception());
        }
        finish_turn(task, wants_more, lane, thread_cpu_time() - cpu_start);
    }
}

void WorkerPool::offer(const std::shared_ptr<HelpOffer>& offer, unsigned threads) {
    offer_charged(offer, threads, nullptr);
}

void WorkerPool::offer_charged(const std::shared_ptr<HelpOffer>& offer, unsigned threads,
                               std::shared_ptr<std::atomic<Clock::rep>> cpu) {
    if (threads == 0) return;
    {
        std::lock_guard lock(mutex_);
        if (stopping_) return;
        offers_.push_back({offer, threads, std::move(cpu)});
    }
    for (unsigned i = 0; i < threads; ++i) wake_.notify_one();
}

void WorkerPool::withdraw(const HelpOffer& offer) {
    std::lock_guard lock(mutex_);
    std::erase_if(offers_, [&](const OfferEntry& entry) { return entry.offer.get() == &offer; });
}

std::optional<WorkerPool::OfferEntry> WorkerPool::take_offer() {
    if (offers_.empty()) return std::nullopt;
    OfferEntry& first = offers_.front();
    assert(first.threads > 0);
    OfferEntry taken = first;
    if (--first.threads == 0) offers_.pop_front();
    return taken;
}

bool WorkerPool::wanted_back() const {
    return queued_tasks_.load(std::memory_order_relaxed) > 0 ||
           recall_all_.load(std::memory_order_relaxed) ||
           Clock::now().time_since_epoch().count() >= next_timer_.load(std::memory_order_relaxed);
}

void WorkerPool::help(const OfferEntry& entry) {
    const Clock::duration cpu_start = thread_cpu_time();
    const std::size_t items = entry.offer->help([this] { return wanted_back(); });
    if (entry.cpu) *entry.cpu += (thread_cpu_time() - cpu_start).count();
    if (metrics_) metrics_->help_items.add(items);
    std::lock_guard lock(mutex_);
    --helping_;
    if (idle()) idle_.notify_all();
}

void WorkerPool::finish_turn(const std::shared_ptr<Task>& task, bool wants_more, Lane lane,
                             Clock::duration cpu) {
    std::lock_guard lock(mutex_);
    if (lane != Lane::round_robin) lane_time_[static_cast<std::size_t>(lane)] += cpu;
    if (metrics_) metrics_->busy_workers.add(-1);
    --running_;
    const bool rescheduled = task->state_ == Task::State::running_rescheduled;
    // Only a schedule() during the turn keeps its lane; a continuation is round-robin.
    if (!rescheduled) task->lane_ = Lane::round_robin;
    if ((wants_more || rescheduled) && !stopping_) {
        enqueue(task);
    } else {
        task->state_ = Task::State::idle;
    }
    if (idle()) idle_.notify_all();
}

}  // namespace isomesh::server
