#include "server/client.h"

namespace isomesh::server {

Client::Client(std::uint64_t id, std::size_t queue_bytes, std::function<void()> wakeup,
               Metrics* metrics)
    : id_(id), queue_(queue_bytes, std::move(wakeup), metrics) {}

void Client::send(const protocol::ServerMessage& message, bool droppable) {
    queue_.push_text(std::make_shared<const std::string>(protocol::serialize(message)), droppable);
}

bool Client::add_subscription(const protocol::SessionId& session) {
    std::lock_guard lock(mutex_);
    return subscriptions_.insert(session).second;
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

bool Client::reserve_created(std::size_t limit) {
    std::lock_guard lock(mutex_);
    if (created_ >= limit) return false;
    ++created_;
    return true;
}

void Client::release_created() {
    std::lock_guard lock(mutex_);
    if (created_ > 0) --created_;
}

std::size_t Client::created_count() const {
    std::lock_guard lock(mutex_);
    return created_;
}

}  // namespace isomesh::server
