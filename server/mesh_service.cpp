#include "server/mesh_service.h"

#include <algorithm>
#include <random>

namespace isomesh::server {
namespace {

using protocol::ErrorCode;
using protocol::MessageType;

SessionSettings session_settings(const ServerConfig& config) {
    SessionSettings s;
    s.slice = std::chrono::microseconds(config.slice_us);
    s.first_mesh_budget = std::chrono::milliseconds(config.first_mesh_ms);
    s.batch_interval = std::chrono::milliseconds(config.batch_ms);
    s.batch_triangles = config.batch_triangles;
    s.eval_timeout = std::chrono::milliseconds(config.eval_timeout_ms);
    s.session_cpu = std::chrono::duration_cast<Clock::duration>(
        std::chrono::duration<double>(config.session_cpu_s));
    s.session_memory_bytes = config.session_memory_mb << 20;
    s.encoding_speed = static_cast<int>(config.draco_speed);
    return s;
}

/// The largest triangle budget: the configured one, or less when a session's memory budget
/// cannot hold it.
std::uint64_t max_triangles(const ServerConfig& config) {
    const std::uint64_t memory = config.session_memory_mb << 20;
    const std::uint64_t affordable =
        memory > SessionMemory::kBaseBytes
            ? (memory - SessionMemory::kBaseBytes) / SessionMemory::kBytesPerTriangle
            : 1;
    return std::max<std::uint64_t>(1, std::min(config.max_triangles, affordable));
}

VersionLimits version_limits(const ServerConfig& config) {
    VersionLimits limits;
    limits.max_triangles = max_triangles(config);
    limits.default_triangles = std::min(config.default_triangles, limits.max_triangles);
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

/// The ids of a session rebuilt from `record`; a record written before view ids were kept gets a
/// new one (the caller stores it).
SessionIds restored_ids(const store::SessionRecord& record, std::uint64_t serial) {
    SessionIds ids{record.id, record.view, serial};
    if (ids.view == protocol::SessionId{}) ids.view = random_session_id(route_of(record.id));
    return ids;
}

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
      first_meshes_(config.first_mesh_cache, config.first_mesh_cache_mb << 20),
      pool_(
          resolved_worker_threads(config), &metrics,
          [&logger](std::exception_ptr error) {
              try {
                  std::rethrow_exception(error);
              } catch (const std::exception& e) {
                  logger.error("worker_exception", {{"message", e.what()}});
              } catch (...) {
                  logger.error("worker_exception", {{"message", "unknown"}});
              }
          },
          static_cast<int>(config.worker_nice)),
      persistence_(std::move(store), metrics, logger),
      max_memory_bytes_(resolved_max_memory_bytes(config)),
      housekeeper_([this] { housekeeping(); }) {
    metrics_.sessions_limit.set(static_cast<std::int64_t>(config_.max_sessions));
    metrics_.sessions_per_connection_limit.set(
        static_cast<std::int64_t>(config_.max_sessions_per_connection));
    metrics_.session_memory_limit_bytes.set(
        static_cast<std::int64_t>(config_.session_memory_mb << 20));
    metrics_.session_cpu_limit_seconds.set(static_cast<std::int64_t>(config_.session_cpu_s));
    metrics_.http_connections_limit.set(static_cast<std::int64_t>(config_.max_http_connections));
    metrics_.memory_limit_bytes.set(static_cast<std::int64_t>(max_memory_bytes_));
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
    int version = protocol::kProtocolVersion;
    auto parsed = protocol::parse_client_message(text, parse_limits_, &version);
    if (!parsed) {
        Request request{*this, client, parsed.error().id};
        request.error(protocol::to_reply(parsed.error()));
        return;
    }
    if (!client->speak(version)) {
        Request request{*this, client,
                        std::visit([](const auto& m) { return m.id; }, parsed.value())};
        request.error(ErrorCode::unsupported_version,
                      "this connection speaks protocol version " +
                          std::to_string(client->protocol_version()) +
                          " (its first message's); a connection keeps one version");
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

void MeshService::receive_oversized(const std::shared_ptr<Client>& client, std::uint64_t bytes,
                                    std::optional<protocol::RequestId> id) {
    metrics_.messages_received.add();
    Request request{*this, client, std::move(id)};
    request.error(ErrorCode::too_large, "message of " + std::to_string(bytes) +
                                            " bytes exceeds the limit of " +
                                            std::to_string(config_.max_message_bytes));
}

void MeshService::catch_up(const std::shared_ptr<Client>& client,
                           const std::vector<protocol::SessionId>& sessions) {
    for (const protocol::SessionId& id : sessions) {
        if (auto entry = lookup(id)) {
            entry->session->request_keyframe(client, entry->access, true);
        } else {
            client->queue().forget(id);
        }
    }
}

void MeshService::disconnect(const std::shared_ptr<Client>& client) {
    client->queue().close();
    for (const protocol::SessionId& id : client->take_subscriptions()) {
        if (auto entry = lookup(id)) entry->session->unsubscribe(*client, entry->access);
    }
}

// ---- requests ---------------------------------------------------------------------------------

void MeshService::handle(Request& request, const protocol::Create& create) {
    auto& client = request.client;
    if (!client->reserve_created(config_.max_sessions_per_connection)) {
        metrics_.sessions_refused[Metrics::kRefusedPerConnection].add();
        request.error(ErrorCode::too_many_sessions,
                      "this connection already has " +
                          std::to_string(config_.max_sessions_per_connection) +
                          " live sessions it created (the server's maximum; sessions it no "
                          "longer follows count until they expire)");
        return;
    }
    VersionResult version = first_version(create, version_limits_);
    if (!version) {
        client->release_created();
        request.error(version.error());
        return;
    }
    const protocol::SessionState state = version.value().state;
    const auto& route = client->route();
    const SessionIds ids{random_session_id(route), random_session_id(route), next_serial_++};
    std::shared_ptr<MeshSession> session;
    {
        std::lock_guard lock(sessions_mutex_);
        if (auto why = refusal(SessionMemory::projected(*state.constraints.triangles))) {
            client->release_created();
            request.error(ErrorCode::server_busy, *why);
            return;
        }
        session = start_session(ids, std::move(version).value(), client);
    }
    if (persistence_.save(ids.control, ids.view, session->latest()) !=
        SessionPersistence::Outcome::ok) {
        remove(ids.control);  // never announced: nothing to tell anyone
        request.error(ErrorCode::store_unavailable, kStoreDown);
        return;
    }
    client->add_subscription(ids.control);
    client->queue().expect_keyframe(ids.control);
    session->subscribe(client, protocol::Access::control, [&] {
        request.reply(
            protocol::Created{request.id, ids.control, state, ids.view, protocol::Access::control});
    });
    logger_.info("session_created", {{"session", ids.serial},
                                     {"client", client->id()},
                                     {"expression", state.expression.value_or("(vm)")},
                                     {"triangles", *state.constraints.triangles}});
}

void MeshService::handle(Request& request, const protocol::Update& update) {
    auto entry = named_session(request, update.session, true);
    if (!entry) return;
    const auto& session = entry->session;
    if (update.constraints && update.constraints->triangles) {
        std::lock_guard lock(sessions_mutex_);
        const std::uint64_t wanted = SessionMemory::projected(*update.constraints->triangles);
        const std::uint64_t held = session->reservation();
        if (auto why = wanted > held ? refusal(wanted, held) : std::nullopt) {
            request.error(ErrorCode::server_busy, *why, update.session);
            return;
        }
    }
    bool moved_away = false;
    session->update(update, version_limits_, *request.client, [&](const VersionResult& result) {
        if (!result) {
            protocol::ErrorReply error = result.error();
            error.session = update.session;
            request.error(std::move(error));
            return false;
        }
        // The record before `updated` leaves.
        switch (persistence_.save(session->id(), session->view_id(), result.value())) {
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
        request.reply(protocol::Updated{request.id, update.session, result.value().state,
                                        session->view_id(), protocol::Access::control});
        return true;
    });
    if (moved_away) moved({update.session});
}

void MeshService::handle(Request& request, const protocol::Subscribe& subscribe) {
    auto entry = named_session(request, subscribe.session, false);
    if (!entry) return;
    auto& client = request.client;
    const auto& session = entry->session;
    const protocol::Access access = entry->access;
    const bool control = access == protocol::Access::control;
    client->add_subscription(subscribe.session);
    client->queue().expect_keyframe(subscribe.session);
    const protocol::SessionState state = session->latest().state;
    const bool subscribed = session->subscribe(client, access, [&] {
        request.reply(protocol::Subscribed{
            request.id, subscribe.session, state,
            control ? std::optional<protocol::SessionId>(session->view_id()) : std::nullopt,
            access});
    });
    if (!subscribed) {
        client->remove_subscription(subscribe.session);
        client->queue().forget(subscribe.session);
        request.error(ErrorCode::unknown_session, "the session has ended", subscribe.session);
    }
}

void MeshService::handle(Request& request, const protocol::Unsubscribe& unsubscribe) {
    auto entry = named_session(request, unsubscribe.session, false);
    if (!entry) return;
    request.client->remove_subscription(unsubscribe.session);
    request.client->queue().forget(unsubscribe.session);
    entry->session->unsubscribe(*request.client, entry->access);
    request.ack(MessageType::unsubscribe, unsubscribe.session);
}

void MeshService::handle(Request& request, const protocol::Pause& pause) {
    auto entry = named_session(request, pause.session, true);
    if (!entry) return;
    entry->session->set_paused(true);
    request.ack(MessageType::pause, pause.session);
}

void MeshService::handle(Request& request, const protocol::Resume& resume) {
    auto entry = named_session(request, resume.session, true);
    if (!entry) return;
    request.ack(MessageType::resume, resume.session);
    entry->session->set_paused(false);
}

void MeshService::handle(Request& request, const protocol::Close& close) {
    // A session served elsewhere comes here first.
    if (!named_session(request, close.session, true)) return;
    auto session = remove(close.session);
    if (!session) {
        request.error(ErrorCode::unknown_session, "the session has ended", close.session);
        return;
    }
    persistence_.remove(close.session);  // before the ack: a closed session never comes back
    request.ack(MessageType::close, close.session);
    session->close(protocol::Closed::Reason::closed);
    logger_.info("session_closed", {{"session", session->serial()}, {"reason", "closed"}});
}

void MeshService::handle(Request& request, const protocol::Resync& resync) {
    auto entry = named_session(request, resync.session, false);
    if (!entry) return;
    if (!request.client->subscribed(resync.session)) {
        request.error(ErrorCode::unknown_session, "this connection does not follow the session",
                      resync.session);
        return;
    }
    request.client->queue().expect_keyframe(resync.session);
    request.ack(MessageType::resync, resync.session);
    entry->session->request_keyframe(request.client, entry->access, true);
}

void MeshService::handle(Request& request, const protocol::Ping&) {
    request.reply(protocol::Pong{request.id, unix_time_us(), limits()});
}

protocol::ServerLimits MeshService::limits() const {
    protocol::ServerLimits l;
    l.message_bytes = config_.max_message_bytes;
    l.sessions_per_connection = config_.max_sessions_per_connection;
    l.triangles = version_limits_.max_triangles;
    l.session_memory_bytes = config_.session_memory_mb << 20;
    l.eval_cpu_s = config_.eval_timeout_ms / 1000.0;
    l.session_cpu_s = config_.session_cpu_s;
    l.idle_timeout_s = config_.idle_timeout_s;
    l.orphan_timeout_s = config_.orphan_timeout_s;
    return l;
}

std::optional<MeshService::Entry> MeshService::named_session(Request& request,
                                                             const protocol::SessionId& id,
                                                             bool control) {
    auto entry = lookup(id);
    if (!entry) entry = restore(request, id);
    if (!entry) return std::nullopt;
    if (control && entry->access != protocol::Access::control) {
        request.error(ErrorCode::read_only,
                      "this is the session's view id: it can subscribe, unsubscribe and resync; "
                      "updating, pausing, resuming and closing need the control id",
                      id);
        return std::nullopt;
    }
    entry->session->touch();
    return entry;
}

std::optional<MeshService::Entry> MeshService::restore(Request& request,
                                                       const protocol::SessionId& id) {
    if (!persistence_.enabled()) {
        request.error(ErrorCode::unknown_session, "no live session with this id", id);
        return std::nullopt;
    }
    if (on_another_route(request, id)) return std::nullopt;
    std::lock_guard lock(restore_mutex_);
    if (auto live = lookup(id)) return live;  // rebuilt meanwhile for another request
    auto claimed = persistence_.claim(id);
    if (claimed.outcome == SessionPersistence::Outcome::unavailable) {
        request.error(ErrorCode::store_unavailable, kStoreDown, id);
        return std::nullopt;
    }
    if (!claimed.record) {
        request.error(ErrorCode::unknown_session, "no live session with this id", id);
        return std::nullopt;
    }
    if (!rebuild(request, *claimed.record)) return std::nullopt;
    return lookup(id);
}

bool MeshService::on_another_route(Request& request, const protocol::SessionId& id) {
    const auto& route = request.client->route();
    if (!route || *route == route_of(id) || !persistence_.exists(id)) return false;
    request.error(ErrorCode::wrong_route,
                  "the session is served through route " + route_hex(route_of(id)) + ", not " +
                      route_hex(*route) + ": connect with ?route=" + route_hex(route_of(id)),
                  id);
    return true;
}

std::shared_ptr<MeshSession> MeshService::rebuild(Request& request,
                                                  const store::SessionRecord& record) {
    const std::uint64_t serial = next_serial_++;
    VersionResult version = restorable_version(record, serial);
    if (!version) {
        protocol::ErrorReply error = version.error();
        error.session = record.id;
        request.error(std::move(error));
        return nullptr;
    }
    std::shared_ptr<MeshSession> session;
    {
        std::lock_guard lock(sessions_mutex_);
        // Its record stays: the session may be rebuilt later, here or on another server.
        if (auto why =
                refusal(SessionMemory::projected(*version.value().state.constraints.triangles))) {
            request.error(ErrorCode::server_busy, *why, record.id);
            return nullptr;
        }
        session = start_session(restored_ids(record, serial), std::move(version).value(), nullptr);
    }
    restored(*session, record);
    logger_.info(
        "session_restored",
        {{"session", serial}, {"version", record.version}, {"client", request.client->id()}});
    return session;
}

VersionResult MeshService::restorable_version(const store::SessionRecord& record,
                                              std::uint64_t serial) {
    VersionResult version = restored_version(record, version_limits_);
    if (!version) {
        logger_.warn("session_not_restored",
                     {{"session", serial}, {"message", version.error().message}});
        persistence_.remove(record.id);
    }
    return version;
}

void MeshService::restored(const MeshSession& session, const store::SessionRecord& record) {
    if (session.view_id() != record.view)
        persistence_.save(session.id(), session.view_id(), session.latest());
    metrics_.sessions_restored.add();
}

std::shared_ptr<MeshSession> MeshService::start_session(const SessionIds& ids,
                                                        FunctionVersion version,
                                                        const std::shared_ptr<Client>& creator) {
    auto session = std::make_shared<MeshSession>(
        ids, std::move(version),
        SessionServices{pool_, watchdog_, metrics_, logger_, session_settings(config_),
                        config_.first_mesh_cache > 0 ? &first_meshes_ : nullptr},
        [this](const protocol::SessionId& ended_id) { ended(ended_id); });
    sessions_[ids.control] = Entry{session, protocol::Access::control, creator};
    sessions_[ids.view] = Entry{session, protocol::Access::view, {}};
    return session;
}

void MeshService::reload() {
    if (!persistence_.enabled() || persistence_.shared()) return;  // shared: on demand
    const auto idle_us = static_cast<std::uint64_t>(config_.idle_timeout_s * 1e6);
    const std::uint64_t now_us = unix_time_us();
    std::size_t restored = 0;
    for (const store::SessionRecord& record :
         persistence_.claim_all(now_us > idle_us ? now_us - idle_us : 0)) {
        const std::uint64_t serial = next_serial_++;
        VersionResult version = restorable_version(record, serial);
        if (!version) continue;
        std::shared_ptr<MeshSession> session;
        {
            std::lock_guard lock(sessions_mutex_);
            session =
                start_session(restored_ids(record, serial), std::move(version).value(), nullptr);
        }
        this->restored(*session, record);
        ++restored;
    }
    logger_.info("sessions_reloaded", {{"sessions", restored}});
}

// ---- registry, admission, expiry, shutdown ----------------------------------------------------

std::optional<MeshService::Entry> MeshService::lookup(const protocol::SessionId& id) const {
    std::lock_guard lock(sessions_mutex_);
    auto it = sessions_.find(id);
    if (it == sessions_.end()) return std::nullopt;
    return it->second;
}

std::shared_ptr<MeshSession> MeshService::find(const protocol::SessionId& id) const {
    auto entry = lookup(id);
    return entry ? entry->session : nullptr;
}

std::uint64_t MeshService::reserved_bytes() const {
    std::uint64_t total = 0;
    for (const auto& [id, entry] : sessions_) {
        if (entry.access == protocol::Access::control) total += entry.session->reservation();
    }
    return total;
}

std::optional<std::string> MeshService::refusal(std::uint64_t bytes, std::uint64_t released) const {
    const auto mib = [](std::uint64_t b) { return std::to_string(b >> 20) + " MiB"; };
    if (released == 0 && sessions_.size() / 2 >= config_.max_sessions) {
        metrics_.sessions_refused[Metrics::kRefusedSessions].add();
        return "the server holds its maximum of " + std::to_string(config_.max_sessions) +
               " sessions; try again later";
    }
    const std::uint64_t all = reserved_bytes();
    const std::uint64_t reserved = all - std::min(all, released);
    if (reserved + bytes > max_memory_bytes_) {
        metrics_.sessions_refused[Metrics::kRefusedMemory].add();
        return "the server's memory is reserved by other sessions (" + mib(reserved) + " of " +
               mib(max_memory_bytes_) + "; this budget needs " + mib(bytes) +
               "): try again later or ask for fewer triangles";
    }
    const std::uint64_t resident = resident_bytes();
    if (resident > max_memory_bytes_) {
        metrics_.sessions_refused[Metrics::kRefusedMemory].add();
        return "the server uses " + mib(resident) + ", more than its limit of " +
               mib(max_memory_bytes_) + ": try again later";
    }
    return std::nullopt;
}

std::shared_ptr<MeshSession> MeshService::retire(
    std::map<protocol::SessionId, Entry>::iterator control) {
    auto session = control->second.session;
    if (auto creator = control->second.creator.lock()) creator->release_created();
    sessions_.erase(session->view_id());
    sessions_.erase(control);
    ++sessions_ended_;
    return session;
}

std::shared_ptr<MeshSession> MeshService::remove(const protocol::SessionId& id) {
    std::lock_guard lock(sessions_mutex_);
    auto it = sessions_.find(id);
    if (it == sessions_.end() || it->second.access != protocol::Access::control) return nullptr;
    return retire(it);
}

void MeshService::ended(const protocol::SessionId& id) {
    if (remove(id)) persistence_.remove(id);
}

void MeshService::moved(const std::vector<protocol::SessionId>& sessions) {
    for (const protocol::SessionId& id : sessions) {
        auto session = remove(id);
        if (!session) continue;
        session->close(protocol::Closed::Reason::moved);
        logger_.info("session_moved", {{"session", session->serial()}});
    }
}

std::size_t MeshService::session_count() const {
    std::lock_guard lock(sessions_mutex_);
    return sessions_.size() / 2;
}

void MeshService::shutdown() {
    if (shutting_down_.exchange(true)) return;
    std::vector<std::shared_ptr<MeshSession>> sessions;
    {
        std::lock_guard lock(sessions_mutex_);
        for (const auto& [id, entry] : sessions_) {
            if (entry.access == protocol::Access::control) sessions.push_back(entry.session);
        }
        sessions_.clear();
    }
    // With a store the sessions go on: their records stay, and subscribers are told to come back
    // (to this server once it has restarted, or to the one a load balancer picks).
    const auto reason = persistence_.enabled() ? protocol::Closed::Reason::moved
                                               : protocol::Closed::Reason::shutdown;
    for (const auto& session : sessions) session->close(reason);
    logger_.info("sessions_closed", {{"sessions", sessions.size()}});
}

bool MeshService::wait_workers(Clock::time_point deadline) {
    return pool_.wait_idle(deadline);
}

}  // namespace isomesh::server
