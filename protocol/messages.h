// Control messages: the JSON text frames of the isomesh protocol (PROTOCOL.md, "Control
// messages"; one JSON Schema per message in protocol/schema/). Plain structs, one per message, and
// total parse/serialize functions: parsing validates every field and reports the first problem as
// an error code and a message naming the field; nothing here throws or aborts on any input.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <variant>

#include "protocol/errors.h"

namespace isomesh::protocol {

/// The protocol version this library speaks: the "v" of every message and the version byte of
/// every binary frame.
inline constexpr int kProtocolVersion = 1;
/// The newest version this library speaks: a connection speaks the version of its first message
/// (PROTOCOL.md 9), 1 or 2.
inline constexpr int kMaxProtocolVersion = 2;

/// A session's id: 128 random bits, written in JSON as 32 lowercase hex digits (bytes in order) and
/// in binary frames as the same 16 bytes.
struct SessionId {
    std::array<std::uint8_t, 16> bytes{};

    std::string to_hex() const;
    /// Accepts exactly 32 hex digits, either case.
    static std::optional<SessionId> from_hex(std::string_view hex);
    friend bool operator==(const SessionId&, const SessionId&) = default;
    friend auto operator<=>(const SessionId&, const SessionId&) = default;
};

/// The client-chosen "id" of a request, echoed in its reply: an integer (|id| < 2^53, so that
/// JavaScript clients hold it exactly) or a string of at most kMaxRequestIdBytes bytes.
using RequestId = std::variant<std::int64_t, std::string>;

enum class MessageType {
    // client to server (requests)
    create,
    update,
    subscribe,
    unsubscribe,
    pause,
    resume,
    close,
    resync,
    ping,
    // server to client
    created,
    updated,
    subscribed,
    ack,
    pong,
    progress,
    converged,
    error,
    closed,
};

std::string_view to_string(MessageType type);
std::optional<MessageType> message_type_from_string(std::string_view name);

/// The meshing box [x0, x1] x [y0, y1] x [z0, z1], as the JSON array [x0, x1, y0, y1, z0, z1].
/// Valid boxes are finite with x0 < x1, y0 < y1, z0 < z1.
using Box = std::array<double, 6>;

/// Parameter values by name, e.g. {"a": 1.5}. Values are finite.
using Parameters = std::map<std::string, double>;

/// When refinement stops (PROTOCOL.md, "Constraints"). In a request an absent field means "the
/// server's default" (create) or "unchanged" (update); in a reply every field is present.
struct Constraints {
    std::optional<std::uint64_t> triangles;    ///< triangle budget, >= 1
    std::optional<double> max_error;           ///< error bound, finite and >= 0
    std::optional<std::string> error_measure;  ///< "distance", "epsilon4", "max_distance"
    friend bool operator==(const Constraints&, const Constraints&) = default;
};

/// The function to mesh: an equation in the GeoGebra-like language, or a Fidget .vm program.
struct Source {
    enum class Kind { expression, vm };
    Kind kind = Kind::expression;
    std::string text;
    friend bool operator==(const Source&, const Source&) = default;
};

// ---- client to server -------------------------------------------------------------------------

struct Create {
    std::optional<RequestId> id;
    Source source;
    Parameters parameters;
    Box box{};
    Constraints constraints;
    friend bool operator==(const Create&, const Create&) = default;
};

/// A new function version: at least one of the optional fields is present. `parameters` are merged
/// into the current values; `constraints` fields replace the current ones field by field.
struct Update {
    std::optional<RequestId> id;
    SessionId session;
    std::optional<Source> source;
    std::optional<Parameters> parameters;
    std::optional<Box> box;
    std::optional<Constraints> constraints;
    friend bool operator==(const Update&, const Update&) = default;
};

/// The requests that name a session and nothing else.
template <MessageType T>
struct SessionRequest {
    static constexpr MessageType type = T;
    std::optional<RequestId> id;
    SessionId session;
    friend bool operator==(const SessionRequest&, const SessionRequest&) = default;
};
using Subscribe = SessionRequest<MessageType::subscribe>;
using Unsubscribe = SessionRequest<MessageType::unsubscribe>;
using Pause = SessionRequest<MessageType::pause>;
using Resume = SessionRequest<MessageType::resume>;
using Close = SessionRequest<MessageType::close>;
using Resync = SessionRequest<MessageType::resync>;

struct Ping {
    std::optional<RequestId> id;
    friend bool operator==(const Ping&, const Ping&) = default;
};

using ClientMessage =
    std::variant<Create, Update, Subscribe, Unsubscribe, Pause, Resume, Close, Resync, Ping>;

// ---- server to client -------------------------------------------------------------------------

/// A session's current settings, as the server applies them (every default filled in).
struct SessionState {
    std::uint32_t version = 1;              ///< function version, 1 for `create`, +1 per update
    std::optional<std::string> expression;  ///< the equation (absent for a .vm function)
    Parameters parameters;                  ///< every parameter the function uses, with its value
    Box box{};
    Constraints constraints;  ///< all three fields present
    friend bool operator==(const SessionState&, const SessionState&) = default;
};

/// What the session id a connection holds allows: `control` (the id `created` returns: every
/// request) or `view` (the read-only id: subscribe, unsubscribe and resync only).
enum class Access { control, view };

/// The access's name on the wire ("control", "view").
std::string_view to_string(Access access);
std::optional<Access> access_from_string(std::string_view name);

/// The replies that describe a session: `created`, `updated`, `subscribed`. `updated` without an
/// id also tells every other subscriber of a new version made by someone else.
template <MessageType T>
struct StateReply {
    static constexpr MessageType type = T;
    std::optional<RequestId> id;
    SessionId session;  ///< the id the receiving connection holds (control or view)
    SessionState state;
    /// The session's read-only id, sent only to holders of the control id.
    std::optional<SessionId> view = std::nullopt;
    /// What `session` allows; absent in messages of servers that predate view ids.
    std::optional<Access> access = std::nullopt;
    friend bool operator==(const StateReply&, const StateReply&) = default;
};
using Created = StateReply<MessageType::created>;
using Updated = StateReply<MessageType::updated>;
using Subscribed = StateReply<MessageType::subscribed>;

/// The reply to unsubscribe, pause, resume, close and resync.
struct Ack {
    std::optional<RequestId> id;
    MessageType request = MessageType::pause;  ///< the acknowledged request's type
    SessionId session;
    friend bool operator==(const Ack&, const Ack&) = default;
};

/// The server's limits a client can learn (the `limits` of `pong`).
struct ServerLimits {
    std::uint64_t message_bytes = 0;            ///< largest control message accepted
    std::uint64_t sessions_per_connection = 0;  ///< sessions a connection may create and keep
    std::uint64_t triangles = 0;                ///< largest triangle budget
    std::uint64_t session_memory_bytes = 0;     ///< memory one session may hold
    double eval_cpu_s = 0;        ///< CPU time phase 1 of one function version may take
    double session_cpu_s = 0;     ///< CPU time one session may take over its life
    double idle_timeout_s = 0;    ///< a session without requests for this long expires
    double orphan_timeout_s = 0;  ///< a session without subscribers for this long expires
    friend bool operator==(const ServerLimits&, const ServerLimits&) = default;
};

struct Pong {
    std::optional<RequestId> id;
    std::uint64_t time_us = 0;  ///< server clock, microseconds since the Unix epoch
    std::optional<ServerLimits> limits = std::nullopt;
    friend bool operator==(const Pong&, const Pong&) = default;
};

/// Refinement statistics, sent a few times per second while a session refines.
struct Progress {
    SessionId session;
    std::uint32_t version = 1;
    std::uint64_t sequence = 0;  ///< the last binary frame sent before this message
    std::uint64_t triangles = 0;
    double error_max = 0;
    double error_total = 0;
    double splits_per_second = 0;
    /// Phase 1 is done and proved the topology in every cell (PROTOCOL.md 3.4).
    bool certified = false;
    /// Octree cells meshed without that proof (not yet classified, or unproven).
    std::uint64_t unresolved_cells = 0;
    /// Phase 1 still classifies cells: a keyframe may replace the mesh.
    bool resolving = false;
    friend bool operator==(const Progress&, const Progress&) = default;
};

/// What a function version's mesh is (PROTOCOL.md 3.4).
enum class Outcome { surface, no_surface, region_not_surface };

/// The constraints are met for `version`: the mesh after frame `sequence` is final.
struct Converged {
    SessionId session;
    std::uint32_t version = 1;
    std::uint64_t sequence = 0;
    std::uint64_t triangles = 0;
    double error_max = 0;
    double error_total = 0;
    std::uint64_t splits = 0;
    std::uint64_t merges = 0;
    double first_mesh_ms = 0;  ///< from the version's start to its first mesh (phase 1)
    double total_ms = 0;       ///< from the version's start to convergence
    bool certified = false;
    std::uint64_t unresolved_cells = 0;
    Outcome outcome = Outcome::surface;
    /// The triangle budget is below what the surface's topology needs: `triangles` is the fewest
    /// the server reached.
    bool budget_unreachable = false;
    friend bool operator==(const Converged&, const Converged&) = default;
};

struct ErrorReply {
    std::optional<RequestId> id;
    std::optional<SessionId> session;
    ErrorCode code = ErrorCode::internal;
    std::string message;
    std::optional<std::uint32_t> column;  ///< 1-based column in the expression (bad_expression)
    friend bool operator==(const ErrorReply&, const ErrorReply&) = default;
};

/// A session ended; its subscribers receive nothing more about it.
struct Closed {
    /// moved: the session goes on, but not on this connection (the server is draining, or
    /// another server now serves it): reconnect and subscribe again.
    enum class Reason { closed, expired, shutdown, error, moved };
    SessionId session;
    Reason reason = Reason::closed;
    friend bool operator==(const Closed&, const Closed&) = default;
};

/// The reason's name on the wire ("closed", "expired", "shutdown", "error", "moved").
std::string_view to_string(Closed::Reason reason);
std::optional<Closed::Reason> close_reason_from_string(std::string_view name);
std::string_view to_string(Outcome outcome);
std::optional<Outcome> outcome_from_string(std::string_view name);

using ServerMessage =
    std::variant<Created, Updated, Subscribed, Ack, Pong, Progress, Converged, ErrorReply, Closed>;

// ---- parsing and serializing ------------------------------------------------------------------

/// String lengths are counted in characters (Unicode code points), as JSON Schema's maxLength.
inline constexpr std::size_t kMaxRequestIdCharacters = 64;
inline constexpr std::size_t kMaxParameterNameCharacters = 64;
inline constexpr std::size_t kMaxErrorMeasureBytes = 32;
inline constexpr std::uint64_t kMaxSafeInteger = (std::uint64_t{1} << 53) - 1;

/// Hard limits applied while parsing (PROTOCOL.md, "Limits"). Exceeding a size gives too_large,
/// exceeding the nesting depth gives bad_json.
struct ParseLimits {
    std::size_t max_message_bytes = 1 << 20;
    std::size_t max_expression_bytes = 64 << 10;
    std::size_t max_vm_bytes = 1 << 20;
    std::size_t max_parameters = 256;
    int max_depth = 16;
};

/// Why a request was rejected, with its "id" when one could be read, so that the reply echoes it.
struct RequestError {
    Error error;
    std::optional<RequestId> id;
};

/// A request id from its JSON text (a string or a safe integer, PROTOCOL.md 2), or nothing when
/// the text is not a valid one.
std::optional<RequestId> parse_request_id(std::string_view token);

/// The number of characters (code points) of valid UTF-8 text.
std::size_t utf8_characters(std::string_view text);

/// Parses a client-to-server message. Unknown fields are rejected (bad_field).
/// `version`, when given, receives the message's "v" (1 or 2) once it parsed.
Result<ClientMessage, RequestError> parse_client_message(std::string_view text,
                                                         const ParseLimits& limits = {},
                                                         int* version = nullptr);

/// Parses a server-to-client message. Unknown fields are ignored: servers of the same protocol
/// version may add fields.
Result<ServerMessage> parse_server_message(std::string_view text, const ParseLimits& limits = {});

/// The JSON text of a message (compact, one line). Preconditions: the message is valid (finite
/// numbers, a valid box, ...); a message built by the parsers above always is.
/// `version`: the protocol version the message is written in (its "v"; the fields are the same).
std::string serialize(const ClientMessage& message, int version = kProtocolVersion);
std::string serialize(const ServerMessage& message, int version = kProtocolVersion);

/// The `error` reply to a rejected request.
ErrorReply to_reply(const RequestError& rejected);

}  // namespace isomesh::protocol
