#include "server_mesh.h"

#include <algorithm>
#include <chrono>
#include <fstream>
#include <limits>
#include <sstream>
#include <unordered_map>

#include "args.h"
#include "mesh_export.h"
#include "output.h"
#include "protocol/frame.h"
#include "ws_client.h"

namespace isomesh::cli {
namespace {

using Clock = std::chrono::steady_clock;

/// The server sends `progress` a few times per second while it works: this much silence means
/// it is stuck or gone.
constexpr std::chrono::seconds kIdleTimeout{60};

/// "Phase 1 alone": refinement stops once no triangle's error exceeds the bound, which is then
/// true from the start.
constexpr double kNoRefinementError = 1e300;

constexpr std::int64_t kCreateId = 1;

std::string read_model_file(std::string_view path) {
    std::ifstream file{std::string(path)};
    std::ostringstream text;
    text << file.rdbuf();
    if (!file) throw UsageError("cannot read " + std::string(path));
    return text.str();
}

/// What the server's run produced, gathered while reading its messages.
struct ServerRun {
    std::optional<protocol::SessionId> session;
    protocol::MeshReplica replica;
    std::optional<protocol::Converged> converged;
    std::uint64_t frames = 0;
    std::uint64_t bytes = 0;
    double first_mesh_ms = -1;  ///< client-side: from sending create to the first keyframe

    bool done() const {
        return converged && replica.synchronized() &&
               replica.function_version() == converged->version &&
               replica.sequence() >= converged->sequence;
    }
};

/// Applies one message; returns an error text when the run has failed.
std::optional<std::string> receive(ServerRun& run, const net::WsMessage& message,
                                   net::WsClient& client, Clock::time_point sent) {
    run.bytes += message.data.size();
    if (message.binary) {
        auto frame = protocol::decode_frame(message.bytes());
        if (!frame) return "undecodable frame from the server: " + frame.error().message;
        if (frame.value().header.session != run.session) return std::nullopt;
        ++run.frames;
        if (run.first_mesh_ms < 0 && frame.value().header.kind == protocol::FrameKind::keyframe) {
            run.first_mesh_ms =
                std::chrono::duration<double, std::milli>(Clock::now() - sent).count();
        }
        const auto outcome = run.replica.apply(frame.value());
        if (outcome == protocol::MeshReplica::Outcome::gap ||
            outcome == protocol::MeshReplica::Outcome::inconsistent) {
            client.send_text(protocol::serialize(protocol::Resync{std::nullopt, *run.session}));
        }
        return std::nullopt;
    }
    auto parsed = protocol::parse_server_message(message.data);
    if (!parsed) return "unreadable message from the server: " + parsed.error().message;
    const protocol::ServerMessage& reply = parsed.value();
    if (const auto* created = std::get_if<protocol::Created>(&reply)) {
        if (created->id == protocol::RequestId{kCreateId}) run.session = created->session;
    } else if (const auto* error = std::get_if<protocol::ErrorReply>(&reply)) {
        std::string text = "the server answered " + std::string(protocol::to_string(error->code)) +
                           ": " + error->message;
        if (error->column) text += " (column " + std::to_string(*error->column) + ")";
        return text;
    } else if (const auto* converged = std::get_if<protocol::Converged>(&reply)) {
        if (converged->session == run.session) run.converged = *converged;
    } else if (const auto* closed = std::get_if<protocol::Closed>(&reply)) {
        if (closed->session == run.session) return "the server ended the session";
    }
    return std::nullopt;
}

/// Runs the session to convergence; returns an error text on failure.
std::optional<std::string> run_session(net::WsClient& client, const protocol::Create& create,
                                       ServerRun& run) {
    protocol::Create request = create;
    request.id = kCreateId;
    const Clock::time_point sent = Clock::now();
    client.send_text(protocol::serialize(request));
    while (!run.done()) {
        std::optional<net::WsMessage> message = client.read(Clock::now() + kIdleTimeout);
        if (!message) return "no message from the server for 60 s";
        if (auto failure = receive(run, *message, client, sent)) return failure;
    }
    client.send_text(protocol::serialize(protocol::Close{std::nullopt, *run.session}));
    client.close();
    return std::nullopt;
}

nlohmann::ordered_json server_stats(const ServerRun& run, const Mesh& mesh) {
    nlohmann::ordered_json out;
    out["triangles"] = mesh.triangles.size();
    out["vertices"] = mesh.positions.size();
    out["first_mesh_ms"] = run.converged->first_mesh_ms;
    out["total_ms"] = run.converged->total_ms;
    out["error_total"] = run.converged->error_total;
    out["error_max"] = run.converged->error_max;
    out["splits"] = run.converged->splits;
    out["merges"] = run.converged->merges;
    out["client_first_mesh_ms"] = run.first_mesh_ms;
    out["frames"] = run.frames;
    out["bytes_received"] = run.bytes;
    return out;
}

}  // namespace

protocol::Create server_request(std::string_view source,
                                std::span<const std::string_view> param_items, const Box& box,
                                const RefineOptions& refine) {
    protocol::Create create;
    if (source.starts_with('@')) {
        if (!source.ends_with(".vm")) {
            throw UsageError("--server takes an expression or a @model.vm, not " +
                             std::string(source));
        }
        create.source = {protocol::Source::Kind::vm, read_model_file(source.substr(1))};
    } else {
        create.source = {protocol::Source::Kind::expression, std::string(source)};
    }
    for (const auto& [name, value] : parse_assignments(param_items, "--param")) {
        create.parameters[name] = value;
    }
    create.box = {box.lo.x, box.hi.x, box.lo.y, box.hi.y, box.lo.z, box.hi.z};
    create.constraints.error_measure = refine.error_measure;
    if (!refine.refine()) {
        create.constraints.max_error = kNoRefinementError;
    } else {
        create.constraints.max_error = refine.max_error.value_or(0.0);
        create.constraints.triangles = refine.triangles.value_or(kDefaultTriangleCap);
    }
    return create;
}

Mesh replica_mesh(const protocol::MeshReplica& replica) {
    std::vector<std::uint32_t> ids;
    ids.reserve(replica.vertex_count());
    for (const auto& [id, vertex] : replica.vertices()) ids.push_back(id);
    std::sort(ids.begin(), ids.end());
    Mesh mesh;
    std::unordered_map<std::uint32_t, std::uint32_t> index_of;
    for (std::uint32_t id : ids) {
        const protocol::Vertex& vertex = replica.vertices().at(id);
        index_of[id] = static_cast<std::uint32_t>(mesh.positions.size());
        mesh.positions.emplace_back(vertex.position);
        mesh.normals.emplace_back(vertex.normal);
    }
    for (const protocol::FrameTriangle& triangle : replica.sorted_triangles()) {
        mesh.triangles.push_back({index_of.at(triangle.vertices[0]),
                                  index_of.at(triangle.vertices[1]),
                                  index_of.at(triangle.vertices[2])});
    }
    return mesh;
}

int mesh_on_server(std::string_view url_text, const protocol::Create& create,
                   const std::string& output, bool stats) {
    net::Url url;
    try {
        url = net::parse_url(url_text);
    } catch (const net::NetError& error) {
        throw UsageError(std::string("--server: ") + error.what());
    }
    if (url.scheme != "ws") throw UsageError("--server: expected ws://HOST:PORT/ws");
    ServerRun run;
    try {
        net::WsClient client(url);
        if (auto failure = run_session(client, create, run)) {
            print_error(url.to_string() + ": " + *failure);
            return 1;
        }
    } catch (const net::NetError& error) {
        print_error(url.to_string() + ": " + error.what());
        return 1;
    }
    const Mesh mesh = replica_mesh(run.replica);
    try {
        write_export_file(mesh, output);
    } catch (const std::runtime_error& error) {
        print_error(error.what());
        return 1;
    }
    if (stats) print_json_line(server_stats(run, mesh));
    return 0;
}

}  // namespace isomesh::cli
