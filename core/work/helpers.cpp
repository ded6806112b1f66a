#include "work/helpers.h"

#include <cassert>
#include <thread>
#include <vector>

namespace isomesh {

std::size_t HelpOffer::help(const Recall& recalled) {
    unsigned slot = 0;
    {
        const std::lock_guard lock(mutex_);
        if (closed_ || started_ == max_) return 0;
        slot = ++started_;
        ++running_;
    }
    std::size_t items = 0;
    try {
        items = (*work_)(slot, recalled);
    } catch (...) {
        const std::lock_guard lock(mutex_);
        if (!error_) error_ = std::current_exception();
    }
    const std::lock_guard lock(mutex_);
    assert(running_ > 0);
    if (--running_ == 0) done_.notify_all();
    return items;
}

void HelpOffer::close() {
    std::unique_lock lock(mutex_);
    closed_ = true;
    done_.wait(lock, [this] { return running_ == 0; });
    if (error_) std::rethrow_exception(error_);
}

unsigned HelpOffer::helpers() const {
    const std::lock_guard lock(mutex_);
    return started_;
}

void run_helped(Helpers* helpers, unsigned max_helpers, const HelpWork& work) {
    const Recall never = [] { return false; };
    if (max_helpers == 0) {
        work(0, never);
        return;
    }
    const auto offer = std::make_shared<HelpOffer>(work, max_helpers);
    std::vector<std::jthread> threads;  // without an executor: one a helper
    if (helpers != nullptr) {
        helpers->offer(offer, max_helpers);
    } else {
        threads.reserve(max_helpers);
        for (unsigned i = 0; i < max_helpers; ++i)
            threads.emplace_back([offer, &never] { offer->help(never); });
    }
    std::exception_ptr error;
    try {
        work(0, never);
    } catch (...) {
        error = std::current_exception();
    }
    if (helpers != nullptr) helpers->withdraw(*offer);
    try {
        offer->close();
    } catch (...) {
        if (!error) error = std::current_exception();
    }
    threads.clear();  // joins: they returned from help() or find the offer closed
    if (error) std::rethrow_exception(error);
}

}  // namespace isomesh
