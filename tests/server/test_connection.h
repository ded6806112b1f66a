// A connection without a network, for the service and session tests: a Client whose output queue
// the test writes out by hand (or not, to play a slow reader), decoding every frame and applying it
// to one protocol::MeshReplica per session, as a real client would.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "protocol/frame.h"
#include "protocol/replica.h"
#include "server/mesh_service.h"

namespace isomesh::server::testing {

class TestConnection {
  public:
    /// `route`: the connection's routing key, as `?route=` gives it.
    explicit TestConnection(MeshService& service, std::optional<Route> route = std::nullopt);
    ~TestConnection();

    void send(std::string_view text);
    void send(const protocol::ClientMessage& message);

    /// Writes out and applies everything queued (nothing while `reading` is false).
    void pump();
    /// Pumps until `done` or `seconds` pass; false on timeout.
    bool wait_for(const std::function<bool()>& done, double seconds = 20);
    /// Disconnects, as a vanished client does.
    void disconnect();

    /// The first message of type T with request id `id` (or any id when nullopt), if any.
    template <class T>
    const T* find(std::optional<protocol::RequestId> id = std::nullopt) const {
        for (const auto& message : messages) {
            const T* typed = std::get_if<T>(&message);
            if (!typed) continue;
            if constexpr (requires { typed->id; }) {
                if (id && typed->id != id) continue;
            }
            return typed;
        }
        return nullptr;
    }
    template <class T>
    std::size_t count() const {
        std::size_t n = 0;
        for (const auto& message : messages) n += std::holds_alternative<T>(message);
        return n;
    }
    /// The `converged` message for `session` at `version`, if it came.
    const protocol::Converged* converged(const protocol::SessionId& session,
                                         std::uint32_t version) const;

    std::shared_ptr<Client> client;
    /// The protocol version of the messages send() writes (PROTOCOL.md 9).
    int version = protocol::kProtocolVersion;
    bool reading = true;
    std::vector<protocol::ServerMessage> messages;
    /// Everything received, messages and frame headers, in the order it arrived.
    std::vector<std::variant<protocol::ServerMessage, protocol::FrameHeader>> received;
    std::map<protocol::SessionId, protocol::MeshReplica> replicas;
    std::vector<protocol::FrameHeader> frames;  // headers of every frame received
    std::vector<protocol::MeshReplica::Outcome> outcomes;
    std::size_t bytes_received = 0;

  private:
    void receive(const Outgoing& message);
    MeshService& service_;
};

/// The replica's triangles as vertex-id triples rotated to start at their smallest id (so that the
/// same triangle compares equal whatever its wire id or starting corner), sorted.
std::vector<std::array<std::uint32_t, 3>> canonical_triangles(const protocol::MeshReplica& mesh);

/// The replica's triangles by the bits of their corners' positions, each rotated to start at its
/// smallest corner, sorted: equal lists mean the same triangles at bit-equal positions, whatever
/// the ids (a rebuilt session numbers its triangles anew).
std::vector<std::array<std::uint32_t, 9>> position_triangles(const protocol::MeshReplica& mesh);

/// Empty when the replica holds the same mesh as `mesh`, whatever its ids (which depend on how
/// often a resolving phase 1 replaced the mesh): every vertex matches one of `mesh` within one
/// step of the session's quantization grid (protocol/mesh_codec.h), and the triangles are the
/// same, with the same orientation. Otherwise the first difference.
std::string compare_on_grid(const protocol::MeshReplica& replica, const Mesh& mesh,
                            const protocol::QuantizationGrid& grid);

/// True when every edge of the replica's mesh is shared by exactly two triangles, with opposite
/// directions (closed and consistently oriented).
bool watertight(const protocol::MeshReplica& mesh);

}  // namespace isomesh::server::testing
