// Parsing control messages (PROTOCOL.md, "Control messages"); message_writers.cpp writes them.
//
// Parsing is total: nlohmann-json's exceptions stay inside this file, every field is checked for
// presence, type and range, and the first problem found becomes the returned error. Nesting depth
// is checked on the raw text before parsing so that no input can make the parser recurse deeply.
#include "protocol/messages.h"

#include "protocol/request_id_scanner.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <utility>

#include <nlohmann/json.hpp>

namespace isomesh::protocol {
namespace {

using json = nlohmann::json;

/// True when no array or object in `text` nests deeper than `max_depth`. Brackets inside strings
/// do not count. Malformed text passes here and fails in the parser.
bool nesting_within(std::string_view text, int max_depth) {
    int depth = 0;
    bool in_string = false;
    bool escaped = false;
    for (char c : text) {
        if (in_string) {
            if (escaped) {
                escaped = false;
            } else if (c == '\\') {
                escaped = true;
            } else if (c == '"') {
                in_string = false;
            }
        } else if (c == '"') {
            in_string = true;
        } else if (c == '[' || c == '{') {
            if (++depth > max_depth) return false;
        } else if (c == ']' || c == '}') {
            --depth;
        }
    }
    return true;
}

/// Reads the fields of one JSON object, remembering the first error and every key looked up, so
/// that the keys never looked up can be reported as unknown.
class FieldReader {
  public:
    FieldReader(const json& object, std::string prefix)
        : object_(object), prefix_(std::move(prefix)) {}

    bool ok() const { return !error_; }
    const std::optional<Error>& error() const { return error_; }
    void adopt(const std::optional<Error>& error) {
        if (error && !error_) error_ = error;
    }

    void fail(ErrorCode code, std::string message) {
        if (!error_) error_ = Error{code, std::move(message)};
    }
    void fail_field(std::string_view key, std::string_view problem) {
        fail(ErrorCode::bad_field, "field " + path(key) + " " + std::string(problem));
    }
    std::string path(std::string_view key) const { return prefix_ + std::string(key); }

    const json* find(std::string_view key) {
        looked_up_.insert(std::string(key));
        if (!ok()) return nullptr;
        auto it = object_.find(key);
        return it == object_.end() ? nullptr : &*it;
    }
    const json* require(std::string_view key) {
        const json* value = find(key);
        if (!value && ok()) fail(ErrorCode::bad_field, "missing field " + path(key));
        return value;
    }

    std::optional<bool> boolean(std::string_view key) {
        const json* value = find(key);
        if (!value) return std::nullopt;
        if (!value->is_boolean()) {
            fail_field(key, "must be true or false");
            return std::nullopt;
        }
        return value->get<bool>();
    }

    std::optional<std::string> string(std::string_view key, bool required, std::size_t max_bytes,
                                      ErrorCode too_long = ErrorCode::bad_field) {
        const json* value = required ? require(key) : find(key);
        if (!value) return std::nullopt;
        if (!value->is_string()) {
            fail_field(key, "must be a string");
            return std::nullopt;
        }
        const auto& text = value->get_ref<const std::string&>();
        if (text.size() > max_bytes) {
            fail(too_long,
                 "field " + path(key) + " is longer than " + std::to_string(max_bytes) + " bytes");
            return std::nullopt;
        }
        return text;
    }

    std::optional<std::uint64_t> unsigned_integer(std::string_view key, bool required,
                                                  std::uint64_t min, std::uint64_t max) {
        const json* value = required ? require(key) : find(key);
        if (!value) return std::nullopt;
        if (!value->is_number_integer()) {
            fail_field(key, "must be an integer");
            return std::nullopt;
        }
        if (value->is_number_unsigned()) {
            const auto n = value->get<std::uint64_t>();
            if (n >= min && n <= max) return n;
        }
        fail_field(key, "must be between " + std::to_string(min) + " and " + std::to_string(max));
        return std::nullopt;
    }

    std::optional<double> number(std::string_view key, bool required, double min) {
        const json* value = required ? require(key) : find(key);
        if (!value) return std::nullopt;
        if (!value->is_number()) {
            fail_field(key, "must be a number");
            return std::nullopt;
        }
        const double x = value->get<double>();
        if (!std::isfinite(x) || x < min) {
            fail_field(key, std::isfinite(min) ? "must be a finite number >= " + format_number(min)
                                               : std::string("must be a finite number"));
            return std::nullopt;
        }
        return x;
    }

    /// A nested object's reader, or nothing (with an error) when the field is not an object.
    std::optional<FieldReader> object(std::string_view key, bool required) {
        const json* value = required ? require(key) : find(key);
        if (!value) return std::nullopt;
        if (!value->is_object()) {
            fail_field(key, "must be an object");
            return std::nullopt;
        }
        return FieldReader(*value, path(key) + ".");
    }

    void reject_unknown_fields() {
        if (!ok()) return;
        for (const auto& [key, value] : object_.items()) {
            if (!looked_up_.contains(key)) {
                fail(ErrorCode::bad_field, "unknown field " + path(key));
                return;
            }
        }
    }

    const json& raw() const { return object_; }

  private:
    static std::string format_number(double x) { return json(x).dump(); }

    const json& object_;
    std::string prefix_;
    std::set<std::string, std::less<>> looked_up_;
    std::optional<Error> error_;
};

// ---- readers of the shared field types -----------------------------------------------------

/// A request id's JSON value as a RequestId, or nothing when it is not a valid one.
std::optional<RequestId> request_id_from_json(const json& value) {
    if (value.is_string()) {
        const auto& text = value.get_ref<const std::string&>();
        if (utf8_characters(text) <= kMaxRequestIdCharacters) return RequestId(text);
    } else if (value.is_number_unsigned()) {
        const auto n = value.get<std::uint64_t>();
        if (n <= kMaxSafeInteger) return RequestId(static_cast<std::int64_t>(n));
    } else if (value.is_number_integer()) {
        const auto n = value.get<std::int64_t>();
        if (n >= -static_cast<std::int64_t>(kMaxSafeInteger)) return RequestId(n);
    }
    return std::nullopt;
}

std::optional<RequestId> read_request_id(FieldReader& in) {
    const json* value = in.find("id");
    if (!value) return std::nullopt;
    if (auto id = request_id_from_json(*value)) return id;
    in.fail_field("id", "must be an integer with |id| < 2^53 or a string of at most " +
                            std::to_string(kMaxRequestIdCharacters) + " characters");
    return std::nullopt;
}

std::optional<SessionId> read_session(FieldReader& in, bool required = true) {
    const auto hex = in.string("session", required, 64);
    if (!hex) return std::nullopt;
    auto id = SessionId::from_hex(*hex);
    if (!id) in.fail_field("session", "must be 32 hex digits");
    return id;
}

std::optional<Box> read_box(FieldReader& in, bool required) {
    const json* value = required ? in.require("box") : in.find("box");
    if (!value) return std::nullopt;
    if (!value->is_array() || value->size() != 6) {
        in.fail_field("box", "must be an array of 6 numbers [x0, x1, y0, y1, z0, z1]");
        return std::nullopt;
    }
    Box box{};
    for (std::size_t i = 0; i < 6; ++i) {
        const json& x = (*value)[i];
        if (!x.is_number() || !std::isfinite(x.get<double>())) {
            in.fail_field("box", "must hold finite numbers");
            return std::nullopt;
        }
        box[i] = x.get<double>();
    }
    for (std::size_t axis = 0; axis < 3; ++axis) {
        if (!(box[2 * axis] < box[2 * axis + 1])) {
            in.fail_field("box", "must have x0 < x1, y0 < y1 and z0 < z1");
            return std::nullopt;
        }
    }
    return box;
}

std::optional<Parameters> read_parameters(FieldReader& in, bool required,
                                          const ParseLimits& limits) {
    auto object = in.object("parameters", required);
    if (!object) return std::nullopt;
    const json& values = object->raw();
    if (values.size() > limits.max_parameters) {
        in.fail(ErrorCode::too_large,
                "more than " + std::to_string(limits.max_parameters) + " parameters");
        return std::nullopt;
    }
    Parameters parameters;
    for (const auto& [name, value] : values.items()) {
        if (name.empty() || utf8_characters(name) > kMaxParameterNameCharacters) {
            in.fail_field("parameters", "names must have 1 to " +
                                            std::to_string(kMaxParameterNameCharacters) +
                                            " characters");
            return std::nullopt;
        }
        const auto x = object->number(name, true, -HUGE_VAL);
        in.adopt(object->error());
        if (!x) return std::nullopt;
        parameters[name] = *x;
    }
    return parameters;
}

bool valid_error_measure(std::string_view name) {
    if (name.empty()) return false;
    for (char c : name) {
        if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_')) return false;
    }
    return true;
}

/// Reads a constraints object; `complete` requires all three fields (replies).
std::optional<Constraints> read_constraints(FieldReader& in, bool required, bool complete,
                                            bool strict) {
    auto object = in.object("constraints", required);
    if (!object) return std::nullopt;
    Constraints c;
    c.triangles = object->unsigned_integer("triangles", complete, 1, kMaxSafeInteger);
    c.max_error = object->number("max_error", complete, 0.0);
    c.error_measure = object->string("error_measure", complete, kMaxErrorMeasureBytes);
    if (c.error_measure && !valid_error_measure(*c.error_measure)) {
        object->fail_field("error_measure", "must be a name of lowercase letters, digits and _");
    }
    if (strict) object->reject_unknown_fields();
    in.adopt(object->error());
    if (!in.ok()) return std::nullopt;
    return c;
}

/// Reads "expression" or "vm": exactly one of them when `required`, at most one otherwise.
std::optional<Source> read_source(FieldReader& in, bool required, const ParseLimits& limits) {
    auto expression =
        in.string("expression", false, limits.max_expression_bytes, ErrorCode::too_large);
    auto vm = in.string("vm", false, limits.max_vm_bytes, ErrorCode::too_large);
    if (!in.ok()) return std::nullopt;
    if (expression && vm) {
        in.fail(ErrorCode::bad_field, "fields expression and vm are exclusive");
        return std::nullopt;
    }
    if (expression) return Source{Source::Kind::expression, std::move(*expression)};
    if (vm) return Source{Source::Kind::vm, std::move(*vm)};
    if (required) in.fail(ErrorCode::bad_field, "missing field expression (or vm)");
    return std::nullopt;
}

std::uint32_t read_version(FieldReader& in, bool required) {
    return static_cast<std::uint32_t>(
        in.unsigned_integer("version", required, 1, UINT32_MAX).value_or(1));
}

std::uint64_t read_count(FieldReader& in, std::string_view key) {
    return in.unsigned_integer(key, true, 0, kMaxSafeInteger).value_or(0);
}

double read_double(FieldReader& in, std::string_view key) {
    return in.number(key, true, 0.0).value_or(0.0);
}

// ---- client messages ------------------------------------------------------------------------

ClientMessage read_create(FieldReader& in, std::optional<RequestId> id, const ParseLimits& limits) {
    Create m;
    m.id = std::move(id);
    m.source = read_source(in, true, limits).value_or(Source{});
    m.parameters = read_parameters(in, false, limits).value_or(Parameters{});
    m.box = read_box(in, true).value_or(Box{});
    m.constraints = read_constraints(in, false, false, true).value_or(Constraints{});
    return m;
}

ClientMessage read_update(FieldReader& in, std::optional<RequestId> id, const ParseLimits& limits) {
    Update m;
    m.id = std::move(id);
    m.session = read_session(in).value_or(SessionId{});
    m.source = read_source(in, false, limits);
    m.parameters = read_parameters(in, false, limits);
    m.box = read_box(in, false);
    m.constraints = read_constraints(in, false, false, true);
    if (in.ok() && !m.source && !m.parameters && !m.box && !m.constraints) {
        in.fail(ErrorCode::bad_field,
                "update needs at least one of expression, vm, parameters, box, constraints");
    }
    return m;
}

template <class Request>
ClientMessage read_session_request(FieldReader& in, std::optional<RequestId> id) {
    Request m;
    m.id = std::move(id);
    m.session = read_session(in).value_or(SessionId{});
    return m;
}

ClientMessage read_client_body(MessageType type, FieldReader& in, std::optional<RequestId> id,
                               const ParseLimits& limits) {
    switch (type) {
        case MessageType::create:
            return read_create(in, std::move(id), limits);
        case MessageType::update:
            return read_update(in, std::move(id), limits);
        case MessageType::subscribe:
            return read_session_request<Subscribe>(in, std::move(id));
        case MessageType::unsubscribe:
            return read_session_request<Unsubscribe>(in, std::move(id));
        case MessageType::pause:
            return read_session_request<Pause>(in, std::move(id));
        case MessageType::resume:
            return read_session_request<Resume>(in, std::move(id));
        case MessageType::close:
            return read_session_request<Close>(in, std::move(id));
        case MessageType::resync:
            return read_session_request<Resync>(in, std::move(id));
        default:
            return Ping{std::move(id)};
    }
}

bool is_client_type(MessageType type) {
    return type <= MessageType::ping;
}

// ---- server messages ------------------------------------------------------------------------

SessionState read_state(FieldReader& in, const ParseLimits& limits) {
    SessionState s;
    s.version = read_version(in, true);
    s.expression = in.string("expression", false, limits.max_expression_bytes);
    s.parameters = read_parameters(in, true, limits).value_or(Parameters{});
    s.box = read_box(in, true).value_or(Box{});
    s.constraints = read_constraints(in, true, true, false).value_or(Constraints{});
    return s;
}

std::optional<SessionId> read_view(FieldReader& in) {
    const auto hex = in.string("view", false, 64);
    if (!hex) return std::nullopt;
    auto id = SessionId::from_hex(*hex);
    if (!id) in.fail_field("view", "must be 32 hex digits");
    return id;
}

std::optional<Access> read_access(FieldReader& in) {
    const auto name = in.string("access", false, 32);
    if (!name) return std::nullopt;
    auto access = access_from_string(*name);
    if (!access) in.fail_field("access", "must be control or view");
    return access;
}

template <class Reply>
ServerMessage read_state_reply(FieldReader& in, std::optional<RequestId> id,
                               const ParseLimits& limits) {
    Reply m;
    m.id = std::move(id);
    m.session = read_session(in).value_or(SessionId{});
    m.state = read_state(in, limits);
    m.view = read_view(in);
    m.access = read_access(in);
    return m;
}

std::optional<ServerLimits> read_limits(FieldReader& in) {
    auto object = in.object("limits", false);
    if (!object) return std::nullopt;
    ServerLimits l;
    l.message_bytes = read_count(*object, "message_bytes");
    l.sessions_per_connection = read_count(*object, "sessions_per_connection");
    l.triangles = read_count(*object, "triangles");
    l.session_memory_bytes = read_count(*object, "session_memory_bytes");
    l.eval_cpu_s = read_double(*object, "eval_cpu_s");
    l.session_cpu_s = read_double(*object, "session_cpu_s");
    l.idle_timeout_s = read_double(*object, "idle_timeout_s");
    l.orphan_timeout_s = read_double(*object, "orphan_timeout_s");
    in.adopt(object->error());
    return l;
}

ServerMessage read_pong(FieldReader& in, std::optional<RequestId> id) {
    Pong m;
    m.id = std::move(id);
    m.time_us = in.unsigned_integer("time_us", true, 0, kMaxSafeInteger).value_or(0);
    m.limits = read_limits(in);
    return m;
}

ServerMessage read_ack(FieldReader& in, std::optional<RequestId> id) {
    Ack m;
    m.id = std::move(id);
    const auto request = in.string("request", true, 32);
    const auto type = request ? message_type_from_string(*request) : std::nullopt;
    const bool acknowledged =
        type && *type >= MessageType::unsubscribe && *type <= MessageType::resync;
    if (acknowledged) {
        m.request = *type;
    } else if (request) {
        in.fail_field("request", "must be one of unsubscribe, pause, resume, close, resync");
    }
    m.session = read_session(in).value_or(SessionId{});
    return m;
}

/// Reads the fields Progress and Converged share.
template <class Statistics>
void read_statistics(FieldReader& in, Statistics& m) {
    m.session = read_session(in).value_or(SessionId{});
    m.version = read_version(in, true);
    m.sequence = read_count(in, "sequence");
    m.triangles = read_count(in, "triangles");
    m.error_max = read_double(in, "error_max");
    m.error_total = read_double(in, "error_total");
    // Added within version 1 (PROTOCOL.md 9): absent from older servers' messages.
    m.certified = in.boolean("certified").value_or(false);
    m.unresolved_cells =
        in.unsigned_integer("unresolved_cells", false, 0, kMaxSafeInteger).value_or(0);
}

ServerMessage read_progress(FieldReader& in) {
    Progress m;
    read_statistics(in, m);
    m.splits_per_second = read_double(in, "splits_per_second");
    m.resolving = in.boolean("resolving").value_or(false);
    return m;
}

ServerMessage read_converged(FieldReader& in) {
    Converged m;
    read_statistics(in, m);
    m.budget_unreachable = in.boolean("budget_unreachable").value_or(false);
    if (const auto outcome = in.string("outcome", false, 32)) {
        // Unknown outcomes (a newer server) read as a surface.
        m.outcome = outcome_from_string(*outcome).value_or(Outcome::surface);
    }
    m.splits = read_count(in, "splits");
    m.merges = read_count(in, "merges");
    m.first_mesh_ms = read_double(in, "first_mesh_ms");
    m.total_ms = read_double(in, "total_ms");
    return m;
}

ServerMessage read_error(FieldReader& in, std::optional<RequestId> id) {
    ErrorReply m;
    m.id = std::move(id);
    m.session = read_session(in, false);
    const auto code = in.string("code", true, 64);
    if (code) {
        const auto parsed = error_code_from_string(*code);
        // A newer server may use codes this client does not know: they read as `internal`.
        m.code = parsed.value_or(ErrorCode::internal);
    }
    m.message = in.string("message", true, 1 << 16).value_or("");
    const auto column = in.unsigned_integer("column", false, 1, UINT32_MAX);
    if (column) m.column = static_cast<std::uint32_t>(*column);
    return m;
}

ServerMessage read_closed(FieldReader& in) {
    Closed m;
    m.session = read_session(in).value_or(SessionId{});
    const auto reason = in.string("reason", true, 32);
    if (!reason) return m;
    const auto parsed = close_reason_from_string(*reason);
    if (parsed) {
        m.reason = *parsed;
    } else {
        in.fail_field("reason", "must be one of closed, expired, shutdown, error, moved");
    }
    return m;
}

ServerMessage read_server_body(MessageType type, FieldReader& in, std::optional<RequestId> id,
                               const ParseLimits& limits) {
    switch (type) {
        case MessageType::created:
            return read_state_reply<Created>(in, std::move(id), limits);
        case MessageType::updated:
            return read_state_reply<Updated>(in, std::move(id), limits);
        case MessageType::subscribed:
            return read_state_reply<Subscribed>(in, std::move(id), limits);
        case MessageType::ack:
            return read_ack(in, std::move(id));
        case MessageType::pong:
            return read_pong(in, std::move(id));
        case MessageType::progress:
            return read_progress(in);
        case MessageType::converged:
            return read_converged(in);
        case MessageType::error:
            return read_error(in, std::move(id));
        default:
            return read_closed(in);
    }
}

// ---- the envelope shared by both directions -------------------------------------------------

/// The parsed JSON document and what its envelope ("v", "type", "id") says.
struct Envelope {
    json document;
    bool parsed = false;  // document holds the text's JSON
    std::optional<MessageType> type;
    std::optional<RequestId> id;
    std::optional<Error> error;
    int version = kProtocolVersion;
};

Envelope read_envelope(std::string_view text, const ParseLimits& limits, bool from_client) {
    Envelope e;
    if (text.size() > limits.max_message_bytes) {
        e.error = Error{ErrorCode::too_large, "message of " + std::to_string(text.size()) +
                                                  " bytes exceeds the limit of " +
                                                  std::to_string(limits.max_message_bytes)};
        return e;
    }
    if (!nesting_within(text, limits.max_depth)) {
        e.error = Error{ErrorCode::bad_json,
                        "JSON nested deeper than " + std::to_string(limits.max_depth) + " levels"};
        return e;
    }
    try {
        e.document = json::parse(text);
        e.parsed = true;
    } catch (const json::parse_error& failure) {
        e.error =
            Error{ErrorCode::bad_json, "invalid JSON at byte " + std::to_string(failure.byte)};
        return e;
    } catch (const json::exception&) {  // e.g. a number beyond double's range
        e.error = Error{ErrorCode::bad_json, "invalid JSON: a number is out of range"};
        return e;
    }
    if (!e.document.is_object()) {
        e.error = Error{ErrorCode::bad_json, "a message must be a JSON object"};
        return e;
    }
    FieldReader in(e.document, "");
    e.id = read_request_id(in);
    const auto version = in.unsigned_integer("v", true, 0, UINT64_MAX);
    if (version && (*version < static_cast<std::uint64_t>(kProtocolVersion) ||
                    *version > static_cast<std::uint64_t>(kMaxProtocolVersion))) {
        in.fail(ErrorCode::unsupported_version, "protocol version " + std::to_string(*version) +
                                                    " is not supported (this peer speaks 1 and " +
                                                    std::to_string(kMaxProtocolVersion) + ")");
    } else if (version) {
        e.version = static_cast<int>(*version);
    }
    const auto type_name = in.string("type", true, 32, ErrorCode::unknown_type);
    if (type_name) {
        e.type = message_type_from_string(*type_name);
        if (!e.type || is_client_type(*e.type) != from_client) {
            e.type.reset();
            in.fail(ErrorCode::unknown_type, "unknown message type \"" + *type_name + "\"");
        }
    }
    e.error = in.error();
    return e;
}

}  // namespace

Result<ClientMessage, RequestError> parse_client_message(std::string_view text,
                                                         const ParseLimits& limits, int* version) {
    Envelope e = read_envelope(text, limits, true);
    if (version) *version = e.version;
    // A message that was never parsed (too large, too deep, not JSON) may still name its id.
    if (e.error && !e.parsed) e.id = scan_request_id(text);
    if (e.error) return RequestError{*e.error, e.id};
    FieldReader in(e.document, "");
    read_request_id(in);  // marks the envelope's keys as known
    in.find("v");
    in.find("type");
    ClientMessage message = read_client_body(*e.type, in, e.id, limits);
    in.reject_unknown_fields();
    if (!in.ok()) return RequestError{*in.error(), e.id};
    return message;
}

Result<ServerMessage> parse_server_message(std::string_view text, const ParseLimits& limits) {
    Envelope e = read_envelope(text, limits, false);
    if (e.error) return *e.error;
    FieldReader in(e.document, "");
    ServerMessage message = read_server_body(*e.type, in, e.id, limits);
    if (!in.ok()) return *in.error();
    return message;
}

ErrorReply to_reply(const RequestError& rejected) {
    ErrorReply reply;
    reply.id = rejected.id;
    reply.code = rejected.error.code;
    reply.message = rejected.error.message;
    return reply;
}

std::optional<RequestId> parse_request_id(std::string_view token) {
    try {
        return request_id_from_json(json::parse(token));
    } catch (const json::exception&) {
        return std::nullopt;
    }
}

std::size_t utf8_characters(std::string_view text) {
    return static_cast<std::size_t>(std::count_if(text.begin(), text.end(), [](char c) {
        return (static_cast<unsigned char>(c) & 0xC0) != 0x80;
    }));
}

}  // namespace isomesh::protocol
