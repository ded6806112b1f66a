#include "server/mesh_service.h"

#include <algorithm>
#include <random>

namespace isomesh::server {
namespace {

using protocol::ErrorCode;
using protocol::MessageType;

std::chrono::milliseconds to_duration(double seconds) {
    return std::chrono::milliseconds(static_cast<std::int64_t>(seconds * 1000.0));
}

SessionSettings session_settings(const ServerConfig& config) {
    SessionSettings s;
    s.slice = std::chrono::microseconds(config.slice_us);
    s.batch_interval = std::chrono::milliseconds(config.batch_ms);
    s.batch_triangles = config.batch_triangles;
    s.eval_timeout = std::chrono::milliseconds(config.eval_timeout_ms);
    s.encoding_speed = static_cast<int>(config.draco_speed);
    return s;
}

VersionLimits version_limits(const ServerConfig& config) {
    VersionLimits limits;
    limits.max_triangles = config.max_triangles;
    limits.default_triangles = config.default_triangles;
    limits.default_max_error = config.default_max_error;
    return limits;
}

protocol::ParseLimits parse_limits(const ServerConfig& config) {
    protocol::ParseLimits limits;
    limits.max_message_bytes = config.max_message_bytes;
    return limits;
}

constexpr const char* kStoreDown =
    "the session store is unreachable: new sessions and changes to sessions are refused until it "
    "answers again (live sessions keep streaming)";

/// How often the time of the last request of each session is stored (idle expiry after a
/// restart, the Redis key's time to live).
Clock::duration activity_interval(const ServerConfig& config) {
    return std::clamp<Clock::duration>(to_duration(config.idle_timeout_s / 4),
                                       std::chrono::milliseconds(100), std::chrono::seconds(60));
}

/// How often a server sharing its store checks that it still owns its live sessions.
constexpr auto kOwnershipInterval = std::chrono::seconds(1);

std::string route_hex(const Route& route) {
    protocol::SessionId id;
    std::copy(route.begin(), route.end(), id.bytes.begin());
    return id.to_hex().substr(0, 8);
}

}  // namespace

protocol::SessionId random_session_id(const std::optional<Route>& route) {
    static std::mutex mutex;
    static std::random_device device;
    std::lock_guard lock(mutex);
    protocol::SessionId id;
    for (std::size_t i = 0; i < id.bytes.size(); i += 4) {
        const std::uint32_t word = device();
        for (std::size_t b = 0; b < 4; ++b)
            id.bytes[i + b] = static_cast<std::uint8_t>(word >> (8 * b));
    }
    if (route) std::copy(route->begin(), route->end(), id.bytes.begin());
    return id;
}

/// One request being answered: the client and the request's id, echoed in the reply.
struct MeshService::Request {
    MeshService& service;
    const std::shared_ptr<Client>& client;
    std::optional<protocol::RequestId> id;

    void reply(const protocol::ServerMessage& message) { client->send(message); }

    void error(protocol::ErrorReply error) {
        error.id = id;
        service.metrics_.errors[static_cast<int>(error.code)].add();
        service.logger_.debug("request_error", {{"client", client->id()},
                                                {"code", protocol::to_string(error.code)},
                                                {"message", error.message}});
        reply(error);
    }

    void error(ErrorCode code, std::string message,
               std::optional<protocol::SessionId> session = std::nullopt) {
        protocol::ErrorReply e;
        e.code = code;
        e.message = std::move(message);
        e.session = session;
        error(std::move(e));
    }

    void ack(MessageType type, const protocol::SessionId& session) {
        reply(protocol::Ack{id, type, session});
    }
};

MeshService::MeshService(const ServerConfig& config, Logger& logger, Metrics& metrics,
                         std::unique_ptr<store::SessionStore> store)
    : config_(config),
      logger_(logger),
      metrics_(metrics),
      version_limits_(version_limits(config)),
      parse_limits_(parse_limits(config)),
      pool_(resolved_worker_threads(config), &metrics,
            [&logger](std::exception_ptr error) {
                try {
                    std::rethrow_exception(error);
                } catch (const std::exception& e) {
                    logger.error("worker_exception", {{"message", e.what()}});
                } catch (...) {
                    logger.error("worker_exception", {{"message", "unknown"}});
                }
            }),
      persistence_(std::move(store), metrics, logger),
      housekeeper_([this] { housekeeping(); }) {
    reload();
}

MeshService::~MeshService() {
    {
        std::lock_guard lock(housekeeping_mutex_);
        stopping_ = true;
    }
    housekeeping_wake_.notify_all();
    housekeeper_.join();
    pool_.stop();
    std::lock_guard lock(sessions_mutex_);
    sessions_.clear();
}

std::shared_ptr<Client> MeshService::connect(std::function<void()> wakeup,
                                             std::optional<Route> route) {
    auto client = std::make_shared<Client>(next_client_id_++, config_.queue_bytes,
                                           std::move(wakeup), &metrics_);
    client->set_route(route);
    return client;
}

std::optional<std::string> MeshService::unready() const {
    if (shutting_down_) return "draining";
    if (!persistence_.available()) return "session store unreachable";
    return std::nullopt;
}

void MeshService::receive(const std::shared_ptr<Client>& client, std::string_view text) {
    metrics_.messages_received.add();
    auto parsed = protocol::parse_client_message(text, parse_limits_);
    if (!parsed) {
        Request request{*this, client, parsed.error().id};
        request.error(protocol::to_reply(parsed.error()));
        return;
    }
    std::visit(
        [&](const auto& message) {
            Request request{*this, client, message.id};
            if (shutting_down_) {
                request.error(ErrorCode::unavailable, "the server is shutting down");
                return;
            }
            handle(request, message);
        },
        parsed.value());
}

void MeshService::receive_binary(const std::shared_ptr<Client>& client) {
    metrics_.messages_received.add();
    Request request{*this, client, std::nullopt};
    request.error(ErrorCode::bad_json, "clients send text messages only (JSON)");
}

void MeshService::catch_up(const std::shared_ptr<Client>& client,
                           const std::vector<protocol::SessionId>& sessions) {
    for (const protocol::SessionId& id : sessions) {
        if (auto session = find(id)) {
            session->request_keyframe(client, true);
        } else {
            client->queue().forget(id);
        }
    }
}

void MeshService::disconnect(const std::shared_ptr<Client>& client) {
    client->queue().close();
    for (const protocol::SessionId& id : client->take_subscriptions()) {
        if (auto session = find(id)) session->unsubscribe(*client);
    }
}

// ---- requests ---------------------------------------------------------------------------------

void MeshService::handle(Request& request, const protocol::Create& create) {
    if (request.client->subscription_count() >= config_.max_sessions_per_connection) {
        request.error(ErrorCode::too_many_sessions,
                      "this connection already follows " +
                          std::to_string(config_.max_sessions_per_connection) +
                          " sessions (the server's maximum)");
        return;
    }
    VersionResult version = first_version(create, version_limits_);
    if (!version) {
        request.error(version.error());
        return;
    }
    const protocol::SessionId id = random_session_id(request.client->route());
    const protocol::SessionState state = version.value().state;
    if (persistence_.save(id, version.value()) != SessionPersistence::Outcome::ok) {
        request.error(ErrorCode::store_unavailable, kStoreDown);
        return;
    }
    auto session = start_session(id, std::move(version).value());
    request.client->add_subscription(id, config_.max_sessions_per_connection);
    request.client->queue().expect_keyframe(id);
    session->subscribe(request.client, [&] {
        request.reply(protocol::Created{request.id, id, state});
    });
    logger_.info("session_created", {{"session", id.to_hex()},
                                     {"client", request.client->id()},
                                     {"expression", state.expression.value_or("(vm)")},
                                     {"triangles", *state.constraints.triangles}});
}

void MeshService::handle(Request& request, const protocol::Update& update) {
    auto session = named_session(request, update.session);
    if (!session) return;
    bool moved_away = false;
    session->update(update, version_limits_, [&](const VersionResult& result) {
        if (!result) {
            protocol::ErrorReply error = result.error();
            error.session = update.session;
            request.error(std::move(error));
            return false;
        }
        switch (persistence_.save(update.session, result.value())) {  // before `updated` leaves
            case SessionPersistence::Outcome::ok:
                break;
            case SessionPersistence::Outcome::moved:
                moved_away = true;
                request.error(ErrorCode::wrong_route,
                              "another server serves this session now: reconnect and send the "
                              "request again",
                              update.session);
                return false;
            default:
                request.error(ErrorCode::store_unavailable, kStoreDown, update.session);
                return false;
        }
        request.reply(protocol::Updated{request.id, update.session, result.value().state});
        return true;
    });
    if (moved_away) moved({update.session});
}

void MeshService::handle(Request& request, const protocol::Subscribe& subscribe) {
    auto session = named_session(request, subscribe.session);
    if (!session) return;
    auto& client = request.client;
    switch (client->add_subscription(subscribe.session, config_.max_sessions_per_connection)) {
        case Client::SubscribeOutcome::limit:
            request.error(ErrorCode::too_many_sessions,
                          "this connection already follows " +
                              std::to_string(config_.max_sessions_per_connection) +
                              " sessions (the server's maximum)",
                          subscribe.session);
            return;
        case Client::SubscribeOutcome::already:
        case Client::SubscribeOutcome::added:
            break;
    }
    client->queue().expect_keyframe(subscribe.session);
    const protocol::SessionState state = session->latest().state;
    const bool subscribed = session->subscribe(client, [&] {
        request.reply(protocol::Subscribed{request.id, subscribe.session, state});
    });
    if (!subscribed) {
        client->remove_subscription(subscribe.session);
        client->queue().forget(subscribe.session);
        request.error(ErrorCode::unknown_session, "the session has ended", subscribe.session);
    }
}

void MeshService::handle(Request& request, const protocol::Unsubscribe& unsubscribe) {
    auto session = named_session(request, unsubscribe.session);
    if (!session) return;
    request.client->remove_subscription(unsubscribe.session);
    request.client->queue().forget(unsubscribe.session);
    session->unsubscribe(*request.client);
    request.ack(MessageType::unsubscribe, unsubscribe.session);
}

void MeshService::handle(Request& request, const protocol::Pause& pause) {
    auto session = named_session(request, pause.session);
    if (!session) return;
    session->set_paused(true);
    request.ack(MessageType::pause, pause.session);
}

void MeshService::handle(Request& request, const protocol::Resume& resume) {
    auto session = named_session(request, resume.session);
    if (!session) return;
    request.ack(MessageType::resume, resume.session);
    session->set_paused(false);
}

void MeshService::handle(Request& request, const protocol::Close& close) {
    if (!named_session(request, close.session)) return;  // one served elsewhere comes here first
    auto session = remove(close.session);
    if (!session) {
        request.error(ErrorCode::unknown_session, "no live session " + close.session.to_hex(),
                      close.session);
        return;
    }
    persistence_.remove(close.session);  // before the ack: a closed session never comes back
    request.ack(MessageType::close, close.session);
    session->close(protocol::Closed::Reason::closed);
    logger_.info("session_closed", {{"session", close.session.to_hex()}, {"reason", "closed"}});
}

void MeshService::handle(Request& request, const protocol::Resync& resync) {
    auto session = named_session(request, resync.session);
    if (!session) return;
    if (!request.client->subscribed(resync.session)) {
        request.error(ErrorCode::unknown_session,
                      "this connection does not follow session " + resync.session.to_hex(),
                      resync.session);
        return;
    }
    request.client->queue().expect_keyframe(resync.session);
    request.ack(MessageType::resync, resync.session);
    session->request_keyframe(request.client, true);
}

void MeshService::handle(Request& request, const protocol::Ping&) {
    request.reply(protocol::Pong{request.id, unix_time_us()});
}

std::shared_ptr<MeshSession> MeshService::named_session(Request& request,
                                                        const protocol::SessionId& id) {
    auto session = find(id);
    if (!session) session = restore(request, id);
    if (!session) return nullptr;
    session->touch();
    return session;
}

std::shared_ptr<MeshSession> MeshService::restore(Request& request, const protocol::SessionId& id) {
    if (!persistence_.enabled()) {
        request.error(ErrorCode::unknown_session, "no live session " + id.to_hex(), id);
        return nullptr;
    }
    if (on_another_route(request, id)) return nullptr;
    std::lock_guard lock(restore_mutex_);
    if (auto live = find(id)) return live;  // rebuilt meanwhile for another request
    auto claimed = persistence_.claim(id);
    if (claimed.outcome == SessionPersistence::Outcome::unavailable) {
        request.error(ErrorCode::store_unavailable, kStoreDown, id);
        return nullptr;
    }
    if (!claimed.record) {
        request.error(ErrorCode::unknown_session, "no live session " + id.to_hex(), id);
        return nullptr;
    }
    return rebuild(request, *claimed.record);
}

bool MeshService::on_another_route(Request& request, const protocol::SessionId& id) {
    const auto& route = request.client->route();
    if (!route || *route == route_of(id) || !persistence_.exists(id)) return false;
    request.error(ErrorCode::wrong_route,
                  "session " + id.to_hex() + " is served through route " + route_hex(route_of(id)) +
                      ", not " + route_hex(*route) +
                      ": connect with ?route=" + route_hex(route_of(id)),
                  id);
    return true;
}

std::shared_ptr<MeshSession> MeshService::rebuild(Request& request,
                                                  const store::SessionRecord& record) {
    VersionResult version = restored_version(record, version_limits_);
    if (!version) {
        logger_.warn("session_not_restored",
                     {{"session", record.id.to_hex()}, {"message", version.error().message}});
        persistence_.remove(record.id);
        protocol::ErrorReply error = version.error();
        error.session = record.id;
        request.error(std::move(error));
        return nullptr;
    }
    auto session = start_session(record.id, std::move(version).value());
    metrics_.sessions_restored.add();
    logger_.info("session_restored", {{"session", record.id.to_hex()},
                                      {"version", record.version},
                                      {"client", request.client->id()}});
    return session;
}

std::shared_ptr<MeshSession> MeshService::start_session(const protocol::SessionId& id,
                                                        FunctionVersion version) {
    auto session = std::make_shared<MeshSession>(
        id, std::move(version),
        SessionServices{pool_, watchdog_, metrics_, logger_, session_settings(config_)},
        [this](const protocol::SessionId& ended_id) { ended(ended_id); });
    std::lock_guard lock(sessions_mutex_);
    sessions_[id] = session;
    return session;
}

void MeshService::reload() {
    if (!persistence_.enabled() || persistence_.shared()) return;  // shared: on demand
    const auto idle_us = static_cast<std::uint64_t>(config_.idle_timeout_s * 1e6);
    const std::uint64_t now_us = unix_time_us();
    std::size_t restored = 0;
    for (const store::SessionRecord& record :
         persistence_.claim_all(now_us > idle_us ? now_us - idle_us : 0)) {
        VersionResult version = restored_version(record, version_limits_);
        if (!version) {
            logger_.warn("session_not_restored",
                         {{"session", record.id.to_hex()}, {"message", version.error().message}});
            persistence_.remove(record.id);
            continue;
        }
        start_session(record.id, std::move(version).value());
        metrics_.sessions_restored.add();
        ++restored;
    }
    logger_.info("sessions_reloaded", {{"sessions", restored}});
}

// ---- registry, expiry, shutdown ---------------------------------------------------------------

std::shared_ptr<MeshSession> MeshService::find(const protocol::SessionId& id) const {
    std::lock_guard lock(sessions_mutex_);
    auto it = sessions_.find(id);
    return it == sessions_.end() ? nullptr : it->second;
}

std::shared_ptr<MeshSession> MeshService::remove(const protocol::SessionId& id) {
    std::lock_guard lock(sessions_mutex_);
    auto it = sessions_.find(id);
    if (it == sessions_.end()) return nullptr;
    auto session = std::move(it->second);
    sessions_.erase(it);
    return session;
}

void MeshService::ended(const protocol::SessionId& id) {
    if (remove(id)) persistence_.remove(id);
}

void MeshService::moved(const std::vector<protocol::SessionId>& sessions) {
    for (const protocol::SessionId& id : sessions) {
        auto session = remove(id);
        if (!session) continue;
        session->close(protocol::Closed::Reason::moved);
        logger_.info("session_moved", {{"session", id.to_hex()}});
    }
}

std::size_t MeshService::session_count() const {
    std::lock_guard lock(sessions_mutex_);
    return sessions_.size();
}

void MeshService::expire(Clock::time_point now) {
    std::vector<std::shared_ptr<MeshSession>> expired;
    {
        std::lock_guard lock(sessions_mutex_);
        for (auto it = sessions_.begin(); it != sessions_.end();) {
            const auto orphaned = it->second->orphaned_since();
            const bool orphan_expired =
                orphaned && now - *orphaned >= to_duration(config_.orphan_timeout_s);
            const bool idle_expired =
                now - it->second->last_request() >= to_duration(config_.idle_timeout_s);
            if (orphan_expired || idle_expired) {
                expired.push_back(std::move(it->second));
                it = sessions_.erase(it);
            } else {
                ++it;
            }
        }
    }
    for (const auto& session : expired) {
        persistence_.remove(session->id());
        session->close(protocol::Closed::Reason::expired);
        metrics_.sessions_expired.add();
        logger_.info("session_expired", {{"session", session->id().to_hex()}});
    }
}

void MeshService::shutdown() {
    if (shutting_down_.exchange(true)) return;
    std::map<protocol::SessionId, std::shared_ptr<MeshSession>> sessions;
    {
        std::lock_guard lock(sessions_mutex_);
        sessions.swap(sessions_);
    }
    // With a store the sessions go on: their records stay, and subscribers are told to come back
    // (to this server once it has restarted, or to the one a load balancer picks).
    const auto reason = persistence_.enabled() ? protocol::Closed::Reason::moved
                                               : protocol::Closed::Reason::shutdown;
    for (const auto& [id, session] : sessions) session->close(reason);
    pool_.wait_idle(Clock::now() + to_duration(config_.drain_timeout_s));
    logger_.info("sessions_closed", {{"sessions", sessions.size()}});
}

std::vector<std::shared_ptr<MeshSession>> MeshService::live_sessions() const {
    std::lock_guard lock(sessions_mutex_);
    std::vector<std::shared_ptr<MeshSession>> live;
    for (const auto& [id, session] : sessions_) live.push_back(session);
    return live;
}

void MeshService::store_activity() {
    const Clock::time_point now = Clock::now();
    const std::uint64_t now_us = unix_time_us();
    std::vector<store::Activity> touched;
    for (const auto& session : live_sessions()) {
        const Clock::time_point last = session->last_request();
        if (last <= activity_kept_) continue;
        const auto ago = std::chrono::duration_cast<std::chrono::microseconds>(now - last);
        touched.push_back({session->id(), now_us - static_cast<std::uint64_t>(ago.count())});
    }
    activity_kept_ = now;
    persistence_.touch(touched);
}

void MeshService::check_ownership() {
    std::vector<protocol::SessionId> ids;
    for (const auto& session : live_sessions()) ids.push_back(session->id());
    auto owners = persistence_.check(ids);
    if (!owners) return;
    moved(owners->moved);
    for (const protocol::SessionId& id : owners->missing) {
        // The record vanished (the store lost it, or its time to live ran out while the store was
        // down): written again, under the registry's lock so that a close cannot slip between.
        std::lock_guard lock(sessions_mutex_);
        auto it = sessions_.find(id);
        if (it != sessions_.end()) persistence_.save(id, it->second->latest());
    }
}

void MeshService::housekeeping() {
    constexpr auto kTick = std::chrono::milliseconds(100);
    std::uint64_t splits_before = metrics_.splits.value();
    Clock::time_point second_start = Clock::now();
    Clock::time_point activity_start = second_start;
    Clock::time_point ownership_start = second_start;
    std::unique_lock lock(housekeeping_mutex_);
    while (!stopping_) {
        housekeeping_wake_.wait_for(lock, kTick);
        if (stopping_) break;
        const Clock::time_point now = Clock::now();
        expire(now);
        persistence_.maintain(now);
        const bool keep = persistence_.enabled() && persistence_.available() && !shutting_down_;
        if (now - activity_start >= activity_interval(config_)) {
            activity_start = now;
            if (keep) store_activity();
        }
        if (now - ownership_start >= kOwnershipInterval) {
            ownership_start = now;
            if (keep && persistence_.shared()) check_ownership();
        }
        if (now - second_start >= std::chrono::seconds(1)) {
            const std::uint64_t splits = metrics_.splits.value();
            metrics_.splits_per_second.set(static_cast<std::int64_t>(
                static_cast<double>(splits - splits_before) / seconds_between(second_start, now)));
            splits_before = splits;
            second_start = now;
        }
    }
}

}  // namespace isomesh::server
