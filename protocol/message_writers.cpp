// Serializing control messages (PROTOCOL.md, "Control messages"): fields in the order the
// specification lists them, optional fields only when present.
#include <variant>

#include <nlohmann/json.hpp>

#include "protocol/messages.h"

namespace isomesh::protocol {
namespace {

using ordered_json = nlohmann::ordered_json;

ordered_json id_json(const RequestId& id) {
    return std::visit([](const auto& value) { return ordered_json(value); }, id);
}

ordered_json envelope(MessageType type, const std::optional<RequestId>& id) {
    ordered_json out = ordered_json::object();
    out["v"] = kProtocolVersion;
    out["type"] = to_string(type);
    if (id) out["id"] = id_json(*id);
    return out;
}

ordered_json box_json(const Box& box) {
    return ordered_json(box);
}

ordered_json parameters_json(const Parameters& parameters) {
    ordered_json out = ordered_json::object();
    for (const auto& [name, value] : parameters) out[name] = value;
    return out;
}

ordered_json constraints_json(const Constraints& c) {
    ordered_json out = ordered_json::object();
    if (c.triangles) out["triangles"] = *c.triangles;
    if (c.max_error) out["max_error"] = *c.max_error;
    if (c.error_measure) out["error_measure"] = *c.error_measure;
    return out;
}

void write_source(ordered_json& out, const Source& source) {
    out[source.kind == Source::Kind::vm ? "vm" : "expression"] = source.text;
}

ordered_json write(const Create& m) {
    ordered_json out = envelope(MessageType::create, m.id);
    write_source(out, m.source);
    if (!m.parameters.empty()) out["parameters"] = parameters_json(m.parameters);
    out["box"] = box_json(m.box);
    const auto constraints = constraints_json(m.constraints);
    if (!constraints.empty()) out["constraints"] = constraints;
    return out;
}

ordered_json write(const Update& m) {
    ordered_json out = envelope(MessageType::update, m.id);
    out["session"] = m.session.to_hex();
    if (m.source) write_source(out, *m.source);
    if (m.parameters) out["parameters"] = parameters_json(*m.parameters);
    if (m.box) out["box"] = box_json(*m.box);
    if (m.constraints) out["constraints"] = constraints_json(*m.constraints);
    return out;
}

template <MessageType T>
ordered_json write(const SessionRequest<T>& m) {
    ordered_json out = envelope(T, m.id);
    out["session"] = m.session.to_hex();
    return out;
}

ordered_json write(const Ping& m) {
    return envelope(MessageType::ping, m.id);
}

template <MessageType T>
ordered_json write(const StateReply<T>& m) {
    ordered_json out = envelope(T, m.id);
    out["session"] = m.session.to_hex();
    out["version"] = m.state.version;
    if (m.state.expression) out["expression"] = *m.state.expression;
    out["parameters"] = parameters_json(m.state.parameters);
    out["box"] = box_json(m.state.box);
    out["constraints"] = constraints_json(m.state.constraints);
    if (m.view) out["view"] = m.view->to_hex();
    if (m.access) out["access"] = to_string(*m.access);
    return out;
}

ordered_json write(const Ack& m) {
    ordered_json out = envelope(MessageType::ack, m.id);
    out["request"] = to_string(m.request);
    out["session"] = m.session.to_hex();
    return out;
}

ordered_json write(const Pong& m) {
    ordered_json out = envelope(MessageType::pong, m.id);
    out["time_us"] = m.time_us;
    if (m.limits) {
        const ServerLimits& l = *m.limits;
        out["limits"] = {{"message_bytes", l.message_bytes},
                         {"sessions_per_connection", l.sessions_per_connection},
                         {"triangles", l.triangles},
                         {"session_memory_bytes", l.session_memory_bytes},
                         {"eval_cpu_s", l.eval_cpu_s},
                         {"session_cpu_s", l.session_cpu_s},
                         {"idle_timeout_s", l.idle_timeout_s},
                         {"orphan_timeout_s", l.orphan_timeout_s}};
    }
    return out;
}

/// The fields Progress and Converged share.
template <class Statistics>
ordered_json statistics_json(MessageType type, const Statistics& m) {
    ordered_json out = envelope(type, std::nullopt);
    out["session"] = m.session.to_hex();
    out["version"] = m.version;
    out["sequence"] = m.sequence;
    out["triangles"] = m.triangles;
    out["error_max"] = m.error_max;
    out["error_total"] = m.error_total;
    out["certified"] = m.certified;
    out["unresolved_cells"] = m.unresolved_cells;
    return out;
}

ordered_json write(const Progress& m) {
    ordered_json out = statistics_json(MessageType::progress, m);
    out["splits_per_second"] = m.splits_per_second;
    out["resolving"] = m.resolving;
    return out;
}

ordered_json write(const Converged& m) {
    ordered_json out = statistics_json(MessageType::converged, m);
    out["outcome"] = to_string(m.outcome);
    out["budget_unreachable"] = m.budget_unreachable;
    out["splits"] = m.splits;
    out["merges"] = m.merges;
    out["first_mesh_ms"] = m.first_mesh_ms;
    out["total_ms"] = m.total_ms;
    return out;
}

ordered_json write(const ErrorReply& m) {
    ordered_json out = envelope(MessageType::error, m.id);
    if (m.session) out["session"] = m.session->to_hex();
    out["code"] = to_string(m.code);
    out["message"] = m.message;
    if (m.column) out["column"] = *m.column;
    return out;
}

ordered_json write(const Closed& m) {
    ordered_json out = envelope(MessageType::closed, std::nullopt);
    out["session"] = m.session.to_hex();
    out["reason"] = to_string(m.reason);
    return out;
}

std::string dump(const ordered_json& out) {
    // Strings came from valid JSON or from the server itself; `replace` keeps dump() from throwing
    // on invalid UTF-8 should a server-made message ever contain some.
    return out.dump(-1, ' ', false, ordered_json::error_handler_t::replace);
}

}  // namespace

std::string serialize(const ClientMessage& message, int version) {
    ordered_json out = std::visit([](const auto& m) { return write(m); }, message);
    out["v"] = version;
    return dump(out);
}

std::string serialize(const ServerMessage& message, int version) {
    ordered_json out = std::visit([](const auto& m) { return write(m); }, message);
    out["v"] = version;
    return dump(out);
}

}  // namespace isomesh::protocol
