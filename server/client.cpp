#include "server/client.h"

namespace isomesh::server {

Client::Client(std::uint64_t id, std::size_t queue_bytes, std::function<void()> wakeup,
               Metrics* metrics)
    : id_(id), queue_(queue_bytes, std::move(wakeup), metrics) {}

void Client::send(const protocol::ServerMessage& message, bool droppable) {
    queue_.push_text(std::make_shared<const std::string>(protocol::serialize(message)), droppable);
}

Client::SubscribeOutcome Client::add_subscription(const protocol::SessionId& session,
                                                  std::size_t limit) {
    std::lock_guard lock(mutex_);
    if (subscriptions_.contains(session)) return SubscribeOutcome::already;
    if (subscriptions_.size() >= limit) return SubscribeOutcome::limit;
    subscriptions_.insert(session);
    return SubscribeOutcome::added;
}

bool Client::remove_subscription(const protocol::SessionId& session) {
    std::lock_guard lock(mutex_);
    return subscriptions_.erase(session) > 0;
}

bool Client::subscribed(const protocol::SessionId& session) const {
    std::lock_guard lock(mutex_);
    return subscriptions_.contains(session);
}

std::size_t Client::subscription_count() const {
    std::lock_guard lock(mutex_);
    return subscriptions_.size();
}

std::vector<protocol::SessionId> Client::take_subscriptions() {
    std::lock_guard lock(mutex_);
    std::vector<protocol::SessionId> out(subscriptions_.begin(), subscriptions_.end());
    subscriptions_.clear();
    return out;
}

}  // namespace isomesh::server
