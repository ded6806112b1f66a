#include "server/log.h"

#include <chrono>
#include <cstdio>
#include <ctime>

namespace isomesh::server {
namespace {

/// UTC with milliseconds, ISO 8601: 2024-05-01T12:34:56.789Z.
std::string utc_timestamp() {
    using namespace std::chrono;
    const auto now = system_clock::now();
    const std::time_t seconds = system_clock::to_time_t(now);
    const auto millis = duration_cast<milliseconds>(now.time_since_epoch()).count() % 1000;
    std::tm parts{};
    gmtime_r(&seconds, &parts);
    char text[64];
    std::snprintf(text, sizeof text, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", parts.tm_year + 1900,
                  parts.tm_mon + 1, parts.tm_mday, parts.tm_hour, parts.tm_min, parts.tm_sec,
                  static_cast<int>(millis));
    return text;
}

}  // namespace

Logger::Logger(LogLevel level)
    : Logger(level, [](std::string_view line) {
          std::fwrite(line.data(), 1, line.size(), stderr);
          std::fflush(stderr);
      }) {}

Logger::Logger(LogLevel level, Sink sink) : level_(level), sink_(std::move(sink)) {}

void Logger::log(LogLevel level, std::string_view event, nlohmann::ordered_json fields) {
    if (!enabled(level)) return;
    nlohmann::ordered_json line = {
        {"time", utc_timestamp()}, {"level", to_string(level)}, {"event", event}};
    if (fields.is_object()) {
        for (auto& [key, value] : fields.items()) line[key] = std::move(value);
    }
    // Replacement of invalid UTF-8 (a hostile expression may contain some) instead of throwing.
    std::string text = line.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
    std::lock_guard lock(mutex_);
    sink_(text);
}

}  // namespace isomesh::server
