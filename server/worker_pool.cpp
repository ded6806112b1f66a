#include "server/worker_pool.h"

#include <algorithm>
#include <cassert>

namespace isomesh::server {

WorkerPool::WorkerPool(unsigned threads, Metrics* metrics, ErrorHandler on_error)
    : metrics_(metrics), on_error_(std::move(on_error)) {
    assert(threads >= 1);
    if (metrics_) metrics_->worker_threads.set(threads);
    for (unsigned i = 0; i < threads; ++i) threads_.emplace_back([this] { work(); });
}

WorkerPool::~WorkerPool() {
    stop();
}

void WorkerPool::schedule(const std::shared_ptr<Task>& task, Lane lane) {
    std::lock_guard lock(mutex_);
    if (stopping_) return;
    const bool urgent = lane == Lane::urgent;
    switch (task->state_) {
        case Task::State::idle:
            task->urgent_ = urgent;
            enqueue(task);
            break;
        case Task::State::running:
            task->state_ = Task::State::running_rescheduled;
            task->urgent_ = urgent;
            break;
        case Task::State::queued:
            if (urgent && !task->urgent_) promote(task);
            break;
        case Task::State::running_rescheduled:
            task->urgent_ = task->urgent_ || urgent;
            break;
    }
}

void WorkerPool::enqueue(const std::shared_ptr<Task>& task) {
    task->state_ = Task::State::queued;
    (task->urgent_ ? urgent_ : queue_).push_back(task);
    if (metrics_) metrics_->run_queue.add(1);
    wake_.notify_one();
}

void WorkerPool::promote(const std::shared_ptr<Task>& task) {
    const auto it = std::find(queue_.begin(), queue_.end(), task);
    assert(it != queue_.end());
    queue_.erase(it);
    task->urgent_ = true;
    urgent_.push_back(task);
}

std::shared_ptr<Task> WorkerPool::next_task() {
    auto& lane = urgent_.empty() ? queue_ : urgent_;
    std::shared_ptr<Task> task = std::move(lane.front());
    lane.pop_front();
    return task;
}

void WorkerPool::stop() {
    {
        std::lock_guard lock(mutex_);
        if (stopping_ && threads_.empty()) return;
        stopping_ = true;
        for (auto* lane : {&urgent_, &queue_}) {
            if (metrics_) metrics_->run_queue.add(-static_cast<std::int64_t>(lane->size()));
            for (auto& task : *lane) task->state_ = Task::State::idle;
            lane->clear();
        }
    }
    wake_.notify_all();
    for (std::thread& thread : threads_) thread.join();
    threads_.clear();
}

bool WorkerPool::wait_idle(Clock::time_point deadline) {
    std::unique_lock lock(mutex_);
    return idle_.wait_until(lock, deadline, [this] { return nothing_queued() && running_ == 0; });
}

std::size_t WorkerPool::queued() const {
    std::lock_guard lock(mutex_);
    return urgent_.size() + queue_.size();
}

void WorkerPool::work() {
    for (;;) {
        std::shared_ptr<Task> task;
        {
            std::unique_lock lock(mutex_);
            wake_.wait(lock, [this] { return stopping_ || !nothing_queued(); });
            if (stopping_) return;
            task = next_task();
            task->state_ = Task::State::running;
            ++running_;
            if (metrics_) metrics_->run_queue.add(-1), metrics_->busy_workers.add(1);
        }
        bool wants_more = false;
        try {
            wants_more = task->run_slice();
        } catch (...) {
            if (on_error_) on_error_(std::current_exception());
        }
        finish_turn(task, wants_more);
    }
}

void WorkerPool::finish_turn(const std::shared_ptr<Task>& task, bool wants_more) {
    std::lock_guard lock(mutex_);
    if (metrics_) metrics_->busy_workers.add(-1);
    --running_;
    const bool rescheduled = task->state_ == Task::State::running_rescheduled;
    // Only a schedule() during the turn keeps the urgent lane; a continuation is round-robin.
    task->urgent_ = rescheduled && task->urgent_;
    if ((wants_more || rescheduled) && !stopping_) {
        enqueue(task);
    } else {
        task->state_ = Task::State::idle;
    }
    if (nothing_queued() && running_ == 0) idle_.notify_all();
}

}  // namespace isomesh::server
