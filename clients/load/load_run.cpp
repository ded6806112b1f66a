#include "load_run.h"

#include <condition_variable>
#include <cstdlib>
#include <mutex>
#include <thread>
#include <vector>

namespace isomesh::load {
namespace {

using namespace std::chrono;
using Clock = steady_clock;

/// How long users get to close cleanly after the stop before they are abandoned.
constexpr seconds kGrace{5};

/// Counts users whose connection has ended.
class FinishLine {
  public:
    void finished() {
        {
            std::lock_guard lock(mutex_);
            ++finished_;
        }
        changed_.notify_all();
    }
    /// True when `count` users finished before `deadline`.
    bool wait(std::size_t count, Clock::time_point deadline) {
        std::unique_lock lock(mutex_);
        return changed_.wait_until(lock, deadline, [&] { return finished_ >= count; });
    }
    std::size_t count() {
        std::lock_guard lock(mutex_);
        return finished_;
    }

  private:
    std::mutex mutex_;
    std::condition_variable changed_;
    std::size_t finished_ = 0;
};

std::optional<MetricSamples> read_metrics(const net::Url& ws_url, std::string& error) {
    try {
        return parse_metrics(net::http_get(ws_url.with("http", "/metrics")));
    } catch (const net::NetError& e) {
        error = e.what();
        return std::nullopt;
    }
}

}  // namespace

MetricSamples parse_metrics(std::string_view text) {
    MetricSamples samples;
    while (!text.empty()) {
        const auto end = text.find('\n');
        std::string_view line = text.substr(0, end);
        text = end == std::string_view::npos ? std::string_view() : text.substr(end + 1);
        if (line.empty() || line.starts_with('#')) continue;
        // The value follows the last space (label values may hold spaces, values never do).
        const auto space = line.rfind(' ');
        if (space == std::string_view::npos || space == 0) continue;
        const std::string value(line.substr(space + 1));
        char* parsed_end = nullptr;
        const double number = std::strtod(value.c_str(), &parsed_end);
        if (parsed_end == value.c_str() || *parsed_end != '\0') continue;
        samples[std::string(line.substr(0, space))] = number;
    }
    return samples;
}

LoadReport run_load(const LoadOptions& options) {
    LoadReport report;
    report.options = options;
    report.metrics_before = read_metrics(options.url, report.metrics_error);

    FinishLine finish_line;
    std::vector<std::shared_ptr<VirtualUser>> users;
    for (std::size_t i = 0; i < options.sessions; ++i) {
        users.push_back(std::make_shared<VirtualUser>(options.mix, i, options.sessions,
                                                      options.user,
                                                      [&finish_line] { finish_line.finished(); }));
    }
    net::WsEventLoop loop(options.threads);
    const Clock::time_point start = Clock::now();
    const Clock::time_point stop_at =
        start + duration_cast<Clock::duration>(duration<double>(options.duration_s));
    std::size_t started = 0;
    for (std::size_t i = 0; i < users.size(); ++i) {
        const double offset =
            options.ramp_s * static_cast<double>(i) / static_cast<double>(users.size());
        const auto at = start + duration_cast<Clock::duration>(duration<double>(offset));
        if (at >= stop_at) break;
        std::this_thread::sleep_until(at);
        users[i]->start(loop, options.url);
        ++started;
    }
    std::this_thread::sleep_until(stop_at);
    for (std::size_t i = 0; i < started; ++i) users[i]->stop();
    finish_line.wait(started, Clock::now() + kGrace);
    report.unfinished = started - finish_line.count();
    report.elapsed_s = duration<double>(Clock::now() - start).count();
    loop.stop();
    for (const auto& user : users) {
        report.stats.merge(user->stats());
        user->release();
    }
    if (report.unfinished > 0) {
        report.stats.connection_errors += report.unfinished;
        report.stats.record_error(std::to_string(report.unfinished) +
                                  " connections did not close within the grace time");
    }
    report.metrics_after = read_metrics(options.url, report.metrics_error);
    return report;
}

}  // namespace isomesh::load
