// The server's logic without the network: connections (Client), control messages, the session
// registry, the worker pool, expiry and shutdown. net/ feeds it the text of each WebSocket message
// and drains each client's output queue; unit tests drive it directly.
//
// With a session store (server/session_persistence.h), a session's record is written before the
// `created` or `updated` reply leaves, deleted when the session is closed, expires or fails, and
// read back when a request names a session that is not live here (after a restart, or on the
// server a load balancer now routes the session's clients to). An unshared store (SQLite) is
// reloaded whole at start.
//
// Every request gets exactly one reply (`created`, `updated`, `subscribed`, `ack`, `pong` or
// `error` with a stable code), echoing its `id`. A bad request never affects the connection or any
// other session.
//
// Admission: a connection may have created at most max_sessions_per_connection live sessions
// (too_many_sessions; an orphaned session counts until it ends); the server holds at most
// max_sessions sessions, and their reservations (each session's triangle budget times the memory
// a triangle costs, server/resources.h) and the process's resident memory stay within the memory
// limit: beyond either, new sessions and budget increases get server_busy while the sessions
// already running keep working.
#pragma once

#include <atomic>
#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <string_view>
#include <thread>

#include "server/client.h"
#include "server/config.h"
#include "server/first_mesh_cache.h"
#include "server/log.h"
#include "server/metrics.h"
#include "server/resources.h"
#include "server/session.h"
#include "server/session_persistence.h"
#include "server/watchdog.h"
#include "server/worker_pool.h"

namespace isomesh::server {

/// 128 bits from the operating system's random source: session ids are capabilities. With a
/// route, its 4 bytes come first and 96 random bits follow.
protocol::SessionId random_session_id(const std::optional<Route>& route = std::nullopt);

class MeshService {
  public:
    /// Starts the worker pool and the housekeeping thread (mesh_service_housekeeping.cpp: expiry,
    /// splits per second, the store's upkeep); reloads the sessions of an unshared `store` (none:
    /// sessions live in memory only).
    MeshService(const ServerConfig& config, Logger& logger, Metrics& metrics,
                std::unique_ptr<store::SessionStore> store = nullptr);
    ~MeshService();
    MeshService(const MeshService&) = delete;
    MeshService& operator=(const MeshService&) = delete;

    /// A new connection. `wakeup`: see OutputQueue. `route`: the `route` of its URL.
    std::shared_ptr<Client> connect(std::function<void()> wakeup,
                                    std::optional<Route> route = std::nullopt);
    /// One text message from `client`.
    void receive(const std::shared_ptr<Client>& client, std::string_view text);
    /// A binary message from `client` (clients send none): answered with bad_json.
    void receive_binary(const std::shared_ptr<Client>& client);
    /// A message over the size limit that the connection did not keep (`bytes` long, `id` as a
    /// scan of it found): answered with too_large.
    void receive_oversized(const std::shared_ptr<Client>& client, std::uint64_t bytes,
                           std::optional<protocol::RequestId> id);
    /// `client`'s queue drained after a stall: its keyframes for these sessions.
    void catch_up(const std::shared_ptr<Client>& client,
                  const std::vector<protocol::SessionId>& sessions);
    /// The connection is gone: its subscriptions end (sessions left without subscribers stop
    /// refining and expire after the orphan timeout).
    void disconnect(const std::shared_ptr<Client>& client);

    /// Ends every session at once with `closed` (reason shutdown, or moved when a store keeps the
    /// sessions for the next server), cancelling the work under way, and refuses new requests
    /// (`unavailable`). Does not wait for the workers.
    void shutdown();
    bool shutting_down() const { return shutting_down_; }
    /// New sessions' first meshes (first_mesh_cache.h; tests look into it).
    FirstMeshCache& first_mesh_cache() { return first_meshes_; }
    /// Why the server should get no new connections now (draining, the store down), if so.
    std::optional<std::string> unready() const;
    /// Waits until no worker is busy, or until `deadline`; true when idle. A worker stuck in work
    /// that does not check its cancel flag keeps it false: the process must then exit without
    /// destroying the service.
    bool wait_workers(Clock::time_point deadline);

    /// Expires sessions idle or orphaned too long at `now`. The housekeeper calls it; public for
    /// tests.
    void expire(Clock::time_point now);

    std::size_t session_count() const;
    /// The session `id` names (its control or its view id).
    std::shared_ptr<MeshSession> find(const protocol::SessionId& id) const;
    const ServerConfig& config() const { return config_; }
    Metrics& metrics() { return metrics_; }
    Logger& logger() { return logger_; }

  private:
    struct Request;
    /// A registry entry: every session is there under its control id and its view id.
    struct Entry {
        std::shared_ptr<MeshSession> session;
        protocol::Access access = protocol::Access::control;
        std::weak_ptr<Client> creator;  // for the control entry
    };
    void handle(Request& request, const protocol::Create& create);
    void handle(Request& request, const protocol::Update& update);
    void handle(Request& request, const protocol::Subscribe& subscribe);
    void handle(Request& request, const protocol::Unsubscribe& unsubscribe);
    void handle(Request& request, const protocol::Pause& pause);
    void handle(Request& request, const protocol::Resume& resume);
    void handle(Request& request, const protocol::Close& close);
    void handle(Request& request, const protocol::Resync& resync);
    void handle(Request& request, const protocol::Ping& ping);

    /// The session a request names (rebuilt from the store when it is not live here), or nothing
    /// after replying unknown_session, wrong_route, store_unavailable or server_busy (or
    /// read_only when `control` is needed and the id is the view id).
    std::optional<Entry> named_session(Request& request, const protocol::SessionId& id,
                                       bool control);
    std::optional<Entry> lookup(const protocol::SessionId& id) const;
    std::optional<Entry> restore(Request& request, const protocol::SessionId& id);
    /// True after replying wrong_route: the connection's route is not `id`'s, whose record exists.
    bool on_another_route(Request& request, const protocol::SessionId& id);
    /// A live session from `record`, or nothing after replying why not.
    std::shared_ptr<MeshSession> rebuild(Request& request, const store::SessionRecord& record);
    /// The latest version of `record` (of session number `serial`), or why it makes none any more
    /// (a limit lowered since): the record is then dropped.
    VersionResult restorable_version(const store::SessionRecord& record, std::uint64_t serial);
    /// Accounts for a session rebuilt from `record`: stores the view id it was given, if new.
    void restored(const MeshSession& session, const store::SessionRecord& record);
    /// Registers a new session under both its ids (no subscriber yet). `creator` counts it among
    /// the sessions it created until it ends. With sessions_mutex_ held.
    std::shared_ptr<MeshSession> start_session(const SessionIds& ids, FunctionVersion version,
                                               const std::shared_ptr<Client>& creator);
    void reload();
    /// Why a session reserving `bytes` (instead of `released`) cannot be admitted now, if so.
    /// With sessions_mutex_ held.
    std::optional<std::string> refusal(std::uint64_t bytes, std::uint64_t released = 0) const;
    std::uint64_t reserved_bytes() const;  // with sessions_mutex_ held
    std::shared_ptr<MeshSession> remove(const protocol::SessionId& id);
    /// Takes a session out of the registry (both ids) and releases its creator's count. With
    /// sessions_mutex_ held; the iterator is the control entry.
    std::shared_ptr<MeshSession> retire(std::map<protocol::SessionId, Entry>::iterator control);
    /// A session ended by itself (evaluation timeout, failure): gone here and from the store.
    void ended(const protocol::SessionId& id);
    /// Another server serves `sessions` now: their subscribers are told to go there.
    void moved(const std::vector<protocol::SessionId>& sessions);
    protocol::ServerLimits limits() const;
    void housekeeping();
    void observe_resources();
    /// The live sessions (each once).
    std::vector<std::shared_ptr<MeshSession>> live_sessions() const;
    /// Stores when live sessions were last named by a request (idle expiry after a restart).
    void store_activity();
    /// (A shared store.) Lets go of the sessions another server took over; writes again the
    /// records that vanished.
    void check_ownership();

    ServerConfig config_;
    Logger& logger_;
    Metrics& metrics_;
    VersionLimits version_limits_;
    protocol::ParseLimits parse_limits_;
    FirstMeshCache first_meshes_;  // before the pool: the sessions' turns use it
    Watchdog watchdog_;
    WorkerPool pool_;
    std::atomic<bool> shutting_down_{false};
    std::atomic<std::uint64_t> next_client_id_{1};
    SessionPersistence persistence_;
    std::mutex restore_mutex_;           // one session rebuilt at a time: never two of one id
    Clock::time_point activity_kept_{};  // last request times stored up to here

    const std::uint64_t max_memory_bytes_;
    std::atomic<std::uint64_t> next_serial_{1};
    std::atomic<std::uint64_t> sessions_ended_{0};  // for the housekeeper's memory trimming

    mutable std::mutex sessions_mutex_;
    std::map<protocol::SessionId, Entry> sessions_;

    std::mutex housekeeping_mutex_;
    std::condition_variable housekeeping_wake_;
    bool stopping_ = false;
    std::thread housekeeper_;
};

}  // namespace isomesh::server
