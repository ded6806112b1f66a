// Helpers (work/helpers.h): a loop's items run once each whoever runs them; helpers run items
// when an executor lends threads, are recalled between items, and an offer no thread took is
// withdrawn (run_helped waits for no one); a helper's exception reaches the caller; a budget on
// the caller's CPU clock read by a helper counts the caller's time.
#include "work/helpers.h"

#include <gtest/gtest.h>

#include <atomic>
#include <ctime>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

#include "work/work_budget.h"

namespace isomesh {
namespace {

/// Items [0, count) handed out dynamically, each run by `run(item, slot)`, and who ran them.
struct Loop {
    explicit Loop(std::size_t count) : count(count), runs(count), slots(count) {}
    HelpWork work(std::function<void(std::size_t, unsigned)> run = {}) {
        return [this, run](unsigned slot, const Recall& recalled) {
            std::size_t items = 0;
            while (!recalled()) {
                const std::size_t i = next++;
                if (i >= count) break;
                ++runs[i];
                slots[i] = slot;
                if (run) run(i, slot);
                ++items;
            }
            return items;
        };
    }
    std::size_t by_helpers() const {
        std::size_t n = 0;
        for (unsigned s : slots) n += s != 0;
        return n;
    }
    std::size_t count;
    std::atomic<std::size_t> next{0};
    std::vector<std::atomic<int>> runs;
    std::vector<unsigned> slots;  // each written by the one thread that ran the item
};

bool each_ran_once(const Loop& loop) {
    for (const auto& r : loop.runs)
        if (r != 1) return false;
    return true;
}

/// An executor whose one thread helps at once: offer() runs the offer on that thread to the end
/// (the caller's share starts after), recalled after `items_before_recall` items.
class EagerHelpers : public Helpers {
  public:
    explicit EagerHelpers(std::size_t items_before_recall = ~std::size_t{0})
        : limit_(items_before_recall) {}
    void offer(const std::shared_ptr<HelpOffer>& offer, unsigned threads) override {
        offered = threads;
        std::size_t asked = 0;
        std::thread([&] { helped = offer->help([&] { return asked++ >= limit_; }); }).join();
    }
    void withdraw(const HelpOffer&) override { ++withdrawn; }
    unsigned offered = 0;
    std::size_t helped = 0;
    int withdrawn = 0;

  private:
    std::size_t limit_;
};

/// An executor that keeps its offers and never helps (every thread busy).
class BusyHelpers : public Helpers {
  public:
    void offer(const std::shared_ptr<HelpOffer>& offer, unsigned) override { kept = offer; }
    void withdraw(const HelpOffer& offer) override { withdrawn = &offer == kept.get(); }
    std::shared_ptr<HelpOffer> kept;
    bool withdrawn = false;
};

TEST(Helpers, run_helped_without_executor_runs_every_item_once_in_distinct_slots) {
    Loop loop(1000);
    run_helped(nullptr, 3, loop.work());
    EXPECT_TRUE(each_ran_once(loop));
    for (unsigned s : loop.slots) EXPECT_LE(s, 3u);
}

TEST(Helpers, run_helped_helpers_run_items_until_none_is_left) {
    EagerHelpers helpers;
    Loop loop(50);
    run_helped(&helpers, 2, loop.work());
    EXPECT_TRUE(each_ran_once(loop));
    EXPECT_EQ(helpers.offered, 2u);
    EXPECT_EQ(helpers.helped, 50u);  // the helper started first and took every item
    EXPECT_EQ(loop.by_helpers(), 50u);
    EXPECT_EQ(helpers.withdrawn, 1);
}

TEST(Helpers, run_helped_recalled_helper_leaves_the_rest_to_the_caller) {
    EagerHelpers helpers(3);
    Loop loop(50);
    run_helped(&helpers, 1, loop.work());
    EXPECT_TRUE(each_ran_once(loop));
    EXPECT_EQ(helpers.helped, 3u);
    EXPECT_EQ(loop.by_helpers(), 3u);
}

TEST(Helpers, run_helped_withdraws_an_offer_no_thread_took_and_a_late_taker_runs_nothing) {
    BusyHelpers helpers;
    Loop loop(20);
    run_helped(&helpers, 4, loop.work());
    EXPECT_TRUE(each_ran_once(loop));
    EXPECT_EQ(loop.by_helpers(), 0u);
    EXPECT_TRUE(helpers.withdrawn);
    // A thread that had taken the offer before the withdrawal: the closed offer does nothing
    // (the loop's work is not touched: ASan would tell).
    ASSERT_NE(helpers.kept, nullptr);
    EXPECT_EQ(helpers.kept->help([] { return false; }), 0u);
    EXPECT_EQ(helpers.kept->helpers(), 0u);
}

TEST(Helpers, run_helped_passes_a_helpers_exception_to_the_caller) {
    EagerHelpers helpers(1);
    Loop loop(10);
    const HelpWork work = loop.work([](std::size_t, unsigned slot) {
        if (slot != 0) throw std::runtime_error("helper failed");
    });
    EXPECT_THROW(run_helped(&helpers, 1, work), std::runtime_error);
    EXPECT_EQ(helpers.helped, 0u);  // its item threw
    EXPECT_TRUE(each_ran_once(loop));
}

TEST(Helpers, run_helped_passes_the_callers_exception_after_the_helpers_returned) {
    EagerHelpers helpers(1);
    Loop loop(200);
    const HelpWork items = loop.work();
    const HelpWork work = [&](unsigned slot, const Recall& recalled) -> std::size_t {
        if (slot == 0) throw std::logic_error("caller failed");
        return items(slot, recalled);
    };
    EXPECT_THROW(run_helped(&helpers, 1, work), std::logic_error);
    EXPECT_EQ(helpers.helped, 1u);  // the helper ran its item, then the caller threw
    EXPECT_EQ(helpers.withdrawn, 1);
}

std::int64_t this_thread_cpu_us() {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return std::int64_t{t.tv_sec} * 1000000 + t.tv_nsec / 1000;
}

TEST(Helpers, helper_reads_the_callers_cpu_budget_and_its_cancellation) {
    std::atomic<bool> cancel{false};
    const WorkBudget budget(5000, WorkBudget::thread_cpu_clock(), &cancel);
    EagerHelpers helpers;  // the caller waits (no CPU time) while the helper works
    std::int64_t helper_spent = 0;
    bool exhausted_on_helper = true, cancelled_on_helper = false;
    Loop loop(2);
    const HelpWork work = loop.work([&](std::size_t i, unsigned slot) {
        if (slot == 0) return;
        if (i == 0) {
            // 20 ms of the helper's CPU time are not the caller's: its budget of 5 ms goes on.
            const std::int64_t start = this_thread_cpu_us();
            while (this_thread_cpu_us() - start < 20000) {
            }
            helper_spent = this_thread_cpu_us() - start;
            exhausted_on_helper = budget.exhausted();
            cancel = true;  // as a new version or a close would
        } else {
            cancelled_on_helper = budget.cancelled();
        }
    });
    run_helped(&helpers, 1, work);
    EXPECT_GE(helper_spent, 20000);
    EXPECT_FALSE(exhausted_on_helper);
    EXPECT_TRUE(cancelled_on_helper);
    EXPECT_TRUE(budget.exhausted());  // cancelled
}

}  // namespace
}  // namespace isomesh
