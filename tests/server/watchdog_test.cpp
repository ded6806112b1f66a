// The watchdog counts the CPU time of the thread that armed it, not the wall clock (issue 14.5).
#include "server/watchdog.h"

#include <gtest/gtest.h>

#include <thread>

#include "server/resources.h"

namespace isomesh::server {
namespace {

using namespace std::chrono_literals;

/// Burns CPU on this thread until `flag` rises or `limit` of CPU time passes; returns the CPU time.
Clock::duration spin_until(const std::atomic<bool>& flag, Clock::duration limit) {
    const Clock::duration start = thread_cpu_time();
    volatile std::uint64_t sink = 0;
    while (!flag && thread_cpu_time() - start < limit) {
        for (int i = 0; i < 10000; ++i) sink = sink + static_cast<std::uint64_t>(i);
    }
    return thread_cpu_time() - start;
}

TEST(Watchdog, fires_once_the_armed_thread_has_used_its_cpu_time) {
    Watchdog watchdog;
    std::atomic<bool> cancel{false}, expired{false};
    Clock::duration used{};
    {
        auto guard = watchdog.arm(50ms, cancel, expired);
        used = spin_until(cancel, 5s);
    }
    EXPECT_TRUE(expired);
    EXPECT_TRUE(cancel);
    EXPECT_GE(used, 50ms);
    EXPECT_LT(used, 5s);
}

TEST(Watchdog, a_thread_that_waits_uses_no_cpu_time_and_is_not_cancelled) {
    Watchdog watchdog;
    std::atomic<bool> cancel{false}, expired{false};
    {
        auto guard = watchdog.arm(30ms, cancel, expired);
        std::this_thread::sleep_for(150ms);  // five times the limit in wall-clock time
    }
    EXPECT_FALSE(expired);
    EXPECT_FALSE(cancel);
}

TEST(Watchdog, disarmed_guard_never_fires) {
    Watchdog watchdog;
    std::atomic<bool> cancel{false}, expired{false};
    { auto guard = watchdog.arm(1ms, cancel, expired); }
    spin_until(cancel, 20ms);
    EXPECT_FALSE(expired);
}

}  // namespace
}  // namespace isomesh::server
