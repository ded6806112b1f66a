// The protocol's stable error codes: the `code` field of an `error` message, also returned by the
// C++ parsers and decoders of this library. Names are part of the wire format (PROTOCOL.md,
// "Error codes"): never rename one, only add new ones at the end.
#pragma once

#include <cassert>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

namespace isomesh::protocol {

enum class ErrorCode {
    bad_json,             ///< not JSON, not an object, nested too deeply
    unsupported_version,  ///< "v" is not a protocol version this peer speaks
    unknown_type,         ///< "type" names no message
    bad_field,            ///< a field is missing, of the wrong type, out of range, or unknown
    unknown_session,      ///< the session id names no live session
    bad_expression,       ///< the expression or .vm text does not compile (see `column`)
    too_large,            ///< a message or field exceeds a size limit
    too_many_sessions,    ///< this connection already holds the maximum number of sessions
    budget_too_large,     ///< the triangle budget exceeds the server's maximum
    eval_timeout,         ///< evaluating the function exceeded the server's time limit
    unavailable,          ///< the server is shutting down and accepts no new work
    internal,             ///< a bug in the server: report it
    bad_frame,            ///< a binary frame is malformed (used by frame decoders)
    store_unavailable,    ///< the session store is down: no new session or update for now
    wrong_route,          ///< the session belongs to another route (PROTOCOL.md, 1 Connection)
    read_only,            ///< the request needs the control id; it named the view id
    server_busy,          ///< the server is at its session or memory limit: try again later
    resource_limit,       ///< the session used up its memory or CPU-time budget
};

inline constexpr int kErrorCodeCount = static_cast<int>(ErrorCode::resource_limit) + 1;

/// The code's wire name, e.g. "bad_json".
std::string_view to_string(ErrorCode code);

/// The code named `name`, or nothing for an unknown name.
std::optional<ErrorCode> error_code_from_string(std::string_view name);

/// What went wrong, for a human: `message` names the offending field or byte offset.
struct Error {
    ErrorCode code = ErrorCode::internal;
    std::string message;
};

/// A value or the reason there is none. The library's functions return these instead of throwing.
template <class T, class E = Error>
class Result {
  public:
    Result(T value) : value_(std::move(value)) {}
    Result(E error) : error_(std::move(error)) {}

    bool ok() const { return value_.has_value(); }
    explicit operator bool() const { return ok(); }

    /// Precondition: ok().
    const T& value() const& {
        assert(ok());
        return *value_;
    }
    T& value() & {
        assert(ok());
        return *value_;
    }
    T&& value() && {
        assert(ok());
        return std::move(*value_);
    }
    /// Precondition: !ok().
    const E& error() const {
        assert(!ok());
        return error_;
    }

  private:
    std::optional<T> value_;
    E error_{};
};

}  // namespace isomesh::protocol
