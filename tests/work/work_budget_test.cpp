// Work budgets (work/work_budget.h): the thread CPU clock, read only when wall time says the end
// may have come, still ends a budget exactly when the thread has spent it.
#include "work/work_budget.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <thread>

namespace isomesh {
namespace {

std::int64_t this_thread_cpu_us() {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return std::int64_t{t.tv_sec} * 1000000 + t.tv_nsec / 1000;
}

TEST(WorkBudget, exhausted_on_the_thread_cpu_clock_ignores_time_the_thread_sleeps) {
    const WorkBudget budget(2000, WorkBudget::thread_cpu_clock());
    // Ten times the budget in wall time, next to none in CPU time: the wall-time bound is past
    // the end, so the clock is read, and says the budget is not spent.
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    EXPECT_FALSE(budget.exhausted());
    EXPECT_LT(budget.elapsed(), 2000);
}

TEST(WorkBudget, exhausted_on_the_thread_cpu_clock_once_the_thread_spent_its_budget) {
    const std::int64_t start = this_thread_cpu_us();
    const WorkBudget budget(2000, WorkBudget::thread_cpu_clock());
    std::uint64_t checks = 0;
    while (!budget.exhausted()) ++checks;
    EXPECT_GE(this_thread_cpu_us() - start, 2000);  // not before
    EXPECT_GT(checks, 0u);
    EXPECT_EQ(budget.remaining(), 0);
}

TEST(WorkBudget, exhausted_on_the_thread_cpu_clock_after_a_sleep_then_work) {
    const std::int64_t start = this_thread_cpu_us();
    const WorkBudget budget(2000, WorkBudget::thread_cpu_clock());
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    EXPECT_FALSE(budget.exhausted());
    while (!budget.exhausted()) {
    }
    EXPECT_GE(this_thread_cpu_us() - start, 2000);
}

TEST(WorkBudget, portion_of_a_thread_cpu_budget_ends_first) {
    const WorkBudget budget(4000, WorkBudget::thread_cpu_clock());
    const WorkBudget half = budget.portion(0.5);
    while (!half.exhausted()) {
    }
    EXPECT_FALSE(budget.exhausted());
    while (!budget.exhausted()) {
    }
    EXPECT_GE(budget.elapsed(), 4000);
}

TEST(WorkBudget, cancelled_ends_a_timed_budget_at_once) {
    std::atomic<bool> cancel{false};
    const WorkBudget budget(1000000, WorkBudget::thread_cpu_clock(), &cancel);
    EXPECT_FALSE(budget.exhausted());
    cancel = true;
    EXPECT_TRUE(budget.exhausted());
}

}  // namespace
}  // namespace isomesh
