// A WebSocket connection as sessions and request handling see it: its output queue, the sessions
// it follows (by the id it holds: control or view) and how many of the live sessions it created.
// Knows nothing of the network (net/ drives the queue).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "protocol/messages.h"
#include "server/output_queue.h"

namespace isomesh::server {

/// A connection's routing key: the `route` query parameter of its WebSocket URL, 8 hex digits
/// (PROTOCOL.md, 1 Connection). Load balancers hash it to pick a server; the sessions the
/// connection creates get it as the first 4 bytes of their ids, so that anyone holding a
/// session id knows the route to the server that serves it.
using Route = std::array<std::uint8_t, 4>;

/// The route of a WebSocket request target such as "/ws?route=0a1b2c3d": nothing when the target
/// has no route parameter, an error message when the parameter is malformed.
protocol::Result<std::optional<Route>, std::string> route_of_target(std::string_view target);

/// The route of a session id (its first 4 bytes).
Route route_of(const protocol::SessionId& id);

class Client {
  public:
    /// `wakeup`: see OutputQueue. `metrics` may be null.
    Client(std::uint64_t id, std::size_t queue_bytes, std::function<void()> wakeup,
           Metrics* metrics);

    std::uint64_t id() const { return id_; }
    OutputQueue& queue() { return queue_; }

    /// Serializes and queues a control message (`droppable`: see OutputQueue::push_text).
    void send(const protocol::ServerMessage& message, bool droppable = false);

    /// Adds `session` (the id this connection holds) to the followed sessions; false when it was
    /// followed already.
    bool add_subscription(const protocol::SessionId& session);
    /// False when `session` was not followed.
    bool remove_subscription(const protocol::SessionId& session);
    bool subscribed(const protocol::SessionId& session) const;
    std::size_t subscription_count() const;
    /// Forgets every subscription (the connection closed) and returns them.
    std::vector<protocol::SessionId> take_subscriptions();

    /// The protocol version this connection speaks (PROTOCOL.md 9): that of its first message
    /// (1 until then). False, changing nothing, when `version` differs from an earlier message's.
    bool speak(int version);
    int protocol_version() const { return version_.load(std::memory_order_relaxed); }

    void set_route(std::optional<Route> route) { route_ = route; }
    const std::optional<Route>& route() const { return route_; }

    /// Counts a session this connection creates, unless `limit` of its sessions are live already
    /// (followed or not: an orphaned session counts until it ends). False at the limit.
    bool reserve_created(std::size_t limit);
    /// One of the sessions this connection created has ended (or was never made).
    void release_created();
    std::size_t created_count() const;

  private:
    const std::uint64_t id_;
    OutputQueue queue_;
    mutable std::mutex mutex_;
    std::set<protocol::SessionId> subscriptions_;
    std::optional<Route> route_;  // set before the first message
    std::size_t created_ = 0;
    std::atomic<int> version_{protocol::kProtocolVersion};
    std::atomic<bool> version_set_{false};
};

}  // namespace isomesh::server
