#include "server/worker_pool.h"

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

void WorkerPool::schedule(const std::shared_ptr<Task>& task) {
    std::lock_guard lock(mutex_);
    if (stopping_) return;
    switch (task->state_) {
        case Task::State::idle:
            task->state_ = Task::State::queued;
            queue_.push_back(task);
            if (metrics_) metrics_->run_queue.add(1);
            wake_.notify_one();
            break;
        case Task::State::running:
            task->state_ = Task::State::running_rescheduled;
            break;
        case Task::State::queued:
        case Task::State::running_rescheduled:
            break;
    }
}

void WorkerPool::stop() {
    {
        std::lock_guard lock(mutex_);
        if (stopping_ && threads_.empty()) return;
        stopping_ = true;
        if (metrics_) metrics_->run_queue.add(-static_cast<std::int64_t>(queue_.size()));
        for (auto& task : queue_) task->state_ = Task::State::idle;
        queue_.clear();
    }
    wake_.notify_all();
    for (std::thread& thread : threads_) thread.join();
    threads_.clear();
}

bool WorkerPool::wait_idle(Clock::time_point deadline) {
    std::unique_lock lock(mutex_);
    return idle_.wait_until(lock, deadline, [this] { return queue_.empty() && running_ == 0; });
}

std::size_t WorkerPool::queued() const {
    std::lock_guard lock(mutex_);
    return queue_.size();
}

void WorkerPool::work() {
    for (;;) {
        std::shared_ptr<Task> task;
        {
            std::unique_lock lock(mutex_);
            wake_.wait(lock, [this] { return stopping_ || !queue_.empty(); });
            if (stopping_) return;
            task = std::move(queue_.front());
            queue_.pop_front();
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
    const bool again = wants_more || task->state_ == Task::State::running_rescheduled;
    if (again && !stopping_) {
        task->state_ = Task::State::queued;
        queue_.push_back(task);
        if (metrics_) metrics_->run_queue.add(1);
        wake_.notify_one();
    } else {
        task->state_ = Task::State::idle;
    }
    if (queue_.empty() && running_ == 0) idle_.notify_all();
}

}  // namespace isomesh::server
