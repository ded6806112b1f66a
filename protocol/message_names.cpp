// The names of the protocol's enumerations on the wire, both ways, and session ids in hex
// (PROTOCOL.md 2 and 7).
#include <array>
#include <optional>
#include <string>
#include <string_view>

#include "protocol/messages.h"

namespace isomesh::protocol {
namespace {

constexpr std::array<std::string_view, kErrorCodeCount> kErrorCodeNames = {
    "bad_json",         "unsupported_version", "unknown_type", "bad_field",
    "unknown_session",  "bad_expression",      "too_large",    "too_many_sessions",
    "budget_too_large", "eval_timeout",        "unavailable",  "internal",
    "bad_frame",        "store_unavailable",   "wrong_route",  "read_only",
    "server_busy",      "resource_limit",
};

constexpr std::array<std::string_view, 18> kMessageTypeNames = {
    "create", "update", "subscribe", "unsubscribe", "pause",   "resume",
    "close",  "resync", "ping",      "created",     "updated", "subscribed",
    "ack",    "pong",   "progress",  "converged",   "error",   "closed",
};

constexpr std::array<std::string_view, 5> kCloseReasonNames = {"closed", "expired", "shutdown",
                                                               "error", "moved"};
constexpr std::array<std::string_view, 3> kOutcomeNames = {"surface", "no_surface",
                                                           "region_not_surface"};

constexpr std::array<std::string_view, 2> kAccessNames = {"control", "view"};

template <class Enum, std::size_t N>
std::optional<Enum> enum_from_name(const std::array<std::string_view, N>& names,
                                   std::string_view name) {
    for (std::size_t i = 0; i < N; ++i) {
        if (names[i] == name) return static_cast<Enum>(i);
    }
    return std::nullopt;
}

}  // namespace

std::string_view to_string(ErrorCode code) {
    return kErrorCodeNames[static_cast<std::size_t>(code)];
}

std::optional<ErrorCode> error_code_from_string(std::string_view name) {
    return enum_from_name<ErrorCode>(kErrorCodeNames, name);
}

std::string_view to_string(MessageType type) {
    return kMessageTypeNames[static_cast<std::size_t>(type)];
}

std::string_view to_string(Closed::Reason reason) {
    return kCloseReasonNames[static_cast<std::size_t>(reason)];
}

std::string_view to_string(Access access) {
    return kAccessNames[static_cast<std::size_t>(access)];
}

std::string_view to_string(Outcome outcome) {
    return kOutcomeNames[static_cast<std::size_t>(outcome)];
}

std::optional<MessageType> message_type_from_string(std::string_view name) {
    return enum_from_name<MessageType>(kMessageTypeNames, name);
}

std::string SessionId::to_hex() const {
    static constexpr char kDigits[] = "0123456789abcdef";
    std::string hex(32, '0');
    for (std::size_t i = 0; i < bytes.size(); ++i) {
        hex[2 * i] = kDigits[bytes[i] >> 4];
        hex[2 * i + 1] = kDigits[bytes[i] & 15];
    }
    return hex;
}

std::optional<SessionId> SessionId::from_hex(std::string_view hex) {
    if (hex.size() != 32) return std::nullopt;
    auto digit = [](char c) -> int {
        if (c >= '0' && c <= '9') return c - '0';
        if (c >= 'a' && c <= 'f') return c - 'a' + 10;
        if (c >= 'A' && c <= 'F') return c - 'A' + 10;
        return -1;
    };
    SessionId id;
    for (std::size_t i = 0; i < id.bytes.size(); ++i) {
        const int high = digit(hex[2 * i]);
        const int low = digit(hex[2 * i + 1]);
        if (high < 0 || low < 0) return std::nullopt;
        id.bytes[i] = static_cast<std::uint8_t>(high * 16 + low);
    }
    return id;
}

std::optional<Access> access_from_string(std::string_view name) {
    return enum_from_name<Access>(kAccessNames, name);
}

std::optional<Outcome> outcome_from_string(std::string_view name) {
    return enum_from_name<Outcome>(kOutcomeNames, name);
}

std::optional<Closed::Reason> close_reason_from_string(std::string_view name) {
    return enum_from_name<Closed::Reason>(kCloseReasonNames, name);
}

}  // namespace isomesh::protocol
