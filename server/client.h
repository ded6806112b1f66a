// A WebSocket connection as sessions and request handling see it: its output queue, the sessions
// it follows (by the id it holds: control or view) and how many of the live sessions it created.
// Knows nothing of the network (net/ drives the queue).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <set>
#include <vector>

#include "protocol/messages.h"
#include "server/output_queue.h"

namespace isomesh::server {

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
    std::size_t created_ = 0;
};

}  // namespace isomesh::server
