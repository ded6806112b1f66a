// Helpers: other threads lending a hand with one thread's parallel loop when they have nothing
// else to do. The thread that owns the work offers it (HelpOffer) to an executor (Helpers) for up
// to N threads, runs the work itself, then withdraws the offers no thread took and waits only for
// the helpers that started. A server's worker pool is such an executor (server/worker_pool.h): a
// lone session's phase 1 then uses every idle core, while a busy server keeps one core a session.
// Without an executor, run_helped starts its own threads (the CLI, the tests and the benches).
//
// The work is a loop over items handed out dynamically: each participant takes items until none
// is left, results stored by item, so the output does not depend on who ran what. A helper is
// recalled between items (its executor wants the thread back for its own tasks); the caller never
// is, so every item runs whatever the helpers do.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>

namespace isomesh {

/// Asked by a helper between items: true when its thread is wanted back.
using Recall = std::function<bool()>;

/// One participant's share of the work: `slot` (0 for the caller, 1, 2, ... for the helpers in
/// the order they started) names its scratch (an evaluator); it runs items until none is left or
/// `recalled()` is true (asked before each item), and returns how many it ran.
using HelpWork = std::function<std::size_t(unsigned slot, const Recall& recalled)>;

/// Work offered to helpers, shared by the caller and the executor. Thread-safe.
class HelpOffer {
  public:
    /// `work` must outlive close(); at most `max_helpers` helpers run it.
    HelpOffer(const HelpWork& work, unsigned max_helpers) : work_(&work), max_(max_helpers) {}

    /// On a helper thread: runs the work in the next slot unless the offer is closed or every
    /// slot is taken. Returns the items it ran (0 when it did not run). An exception from the
    /// work is kept for the caller (close()).
    std::size_t help(const Recall& recalled);

    /// On the caller's thread, once its own share is done: no helper starts after this; waits
    /// for the helpers that started, then rethrows the first exception one of them threw.
    void close();

    /// Helpers that started.
    unsigned helpers() const;

  private:
    const HelpWork* work_;  // not read once closed: the caller's work may be gone
    const unsigned max_;
    mutable std::mutex mutex_;
    std::condition_variable done_;
    bool closed_ = false;
    unsigned started_ = 0;
    unsigned running_ = 0;
    std::exception_ptr error_;
};

/// An executor of help offers: threads that take them when idle.
class Helpers {
  public:
    virtual ~Helpers() = default;
    /// Offers `offer` to up to `threads` threads; each that takes it calls offer->help() once
    /// (on its own thread, with its own recall). Never blocks on the work.
    virtual void offer(const std::shared_ptr<HelpOffer>& offer, unsigned threads) = 0;
    /// Drops the offers of `offer` that no thread took (a thread that took one may still call
    /// help(): the closed offer then does nothing).
    virtual void withdraw(const HelpOffer& offer) = 0;
};

/// Runs `work` on the calling thread (slot 0) and on up to `max_helpers` helpers: threads of
/// `helpers` that are idle, or, when `helpers` is null, as many threads started for the call.
/// Returns once the caller's share is done, the offers no thread took are withdrawn and every
/// helper that started has returned; then rethrows the first exception, the caller's first.
void run_helped(Helpers* helpers, unsigned max_helpers, const HelpWork& work);

}  // namespace isomesh
