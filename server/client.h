// A WebSocket connection as sessions and request handling see it: its output queue and the
// sessions it follows. Knows nothing of the network (net/ drives the queue).
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

    enum class SubscribeOutcome { added, already, limit };
    /// Adds `session` to the followed sessions unless `limit` are followed already.
    SubscribeOutcome add_subscription(const protocol::SessionId& session, std::size_t limit);
    /// False when `session` was not followed.
    bool remove_subscription(const protocol::SessionId& session);
    bool subscribed(const protocol::SessionId& session) const;
    std::size_t subscription_count() const;
    /// Forgets every subscription (the connection closed) and returns them.
    std::vector<protocol::SessionId> take_subscriptions();

  private:
    const std::uint64_t id_;
    OutputQueue queue_;
    mutable std::mutex mutex_;
    std::set<protocol::SessionId> subscriptions_;
};

}  // namespace isomesh::server
