// Structured logs: one JSON object per line, {"time": ..., "level": ..., "event": ..., fields...},
// written whole under a lock so that lines from different threads never interleave.
#pragma once

#include <functional>
#include <mutex>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "server/config.h"

namespace isomesh::server {

class Logger {
  public:
    using Sink = std::function<void(std::string_view line)>;

    /// Writes to stderr.
    explicit Logger(LogLevel level);
    /// Writes each line (with its '\n') to `sink`: for tests.
    Logger(LogLevel level, Sink sink);

    bool enabled(LogLevel level) const { return level >= level_; }

    /// Logs `event` with `fields` (a JSON object, or null for none).
    void log(LogLevel level, std::string_view event, nlohmann::ordered_json fields = nullptr);
    void debug(std::string_view event, nlohmann::ordered_json fields = nullptr) {
        log(LogLevel::debug, event, std::move(fields));
    }
    void info(std::string_view event, nlohmann::ordered_json fields = nullptr) {
        log(LogLevel::info, event, std::move(fields));
    }
    void warn(std::string_view event, nlohmann::ordered_json fields = nullptr) {
        log(LogLevel::warn, event, std::move(fields));
    }
    void error(std::string_view event, nlohmann::ordered_json fields = nullptr) {
        log(LogLevel::error, event, std::move(fields));
    }

  private:
    LogLevel level_;
    Sink sink_;
    std::mutex mutex_;
};

}  // namespace isomesh::server
