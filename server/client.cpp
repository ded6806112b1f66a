#include "server/client.h"

namespace isomesh::server {

protocol::Result<std::optional<Route>, std::string> route_of_target(std::string_view target) {
    const auto query = target.find('?');
    if (query == std::string_view::npos) return std::optional<Route>();
    std::string_view rest = target.substr(query + 1);
    while (!rest.empty()) {
        const auto amp = rest.find('&');
        const std::string_view parameter = rest.substr(0, amp);
        rest = amp == std::string_view::npos ? std::string_view() : rest.substr(amp + 1);
        if (!parameter.starts_with("route=")) continue;
        // 8 hex digits are the first 4 bytes of a session id: pad and parse as one.
        const std::string_view hex = parameter.substr(6);
        auto id = protocol::SessionId::from_hex(std::string(hex) + std::string(24, '0'));
        if (hex.size() != 8 || !id) return std::string("route: expected 8 hex digits");
        return std::optional<Route>(route_of(*id));
    }
    return std::optional<Route>();
}

Route route_of(const protocol::SessionId& id) {
    return {id.bytes[0], id.bytes[1], id.bytes[2], id.bytes[3]};
}

Client::Client(std::uint64_t id, std::size_t queue_bytes, std::function<void()> wakeup,
               Metrics* metrics)
    : id_(id), queue_(queue_bytes, std::move(wakeup), metrics) {}

bool Client::speak(int version) {
    // Messages of one connection are handled one at a time: no race between the two stores.
    if (!version_set_.exchange(true)) {
        version_.store(version, std::memory_order_relaxed);
        return true;
    }
    return version_.load(std::memory_order_relaxed) == version;
}

void Client::send(const protocol::ServerMessage& message, bool droppable) {
    queue_.push_text(
        std::make_shared<const std::string>(protocol::serialize(message, protocol_version())),
        droppable);
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
