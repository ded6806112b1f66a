// The server's logic without the network: connections (Client), control messages, the session
// registry, the worker pool, expiry and shutdown. net/ feeds it the text of each WebSocket message
// and drains each client's output queue; unit tests drive it directly.
//
// Every request gets exactly one reply (`created`, `updated`, `subscribed`, `ack`, `pong` or
// `error` with a stable code), echoing its `id`. A bad request never affects the connection or any
// other session.
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
#include "server/log.h"
#include "server/metrics.h"
#include "server/session.h"
#include "server/watchdog.h"
#include "server/worker_pool.h"

namespace isomesh::server {

/// 128 bits from the operating system's random source: session ids are capabilities.
protocol::SessionId random_session_id();

class MeshService {
  public:
    /// Starts the worker pool and the housekeeping thread (expiry, splits per second).
    MeshService(const ServerConfig& config, Logger& logger, Metrics& metrics);
    ~MeshService();
    MeshService(const MeshService&) = delete;
    MeshService& operator=(const MeshService&) = delete;

    /// A new connection. `wakeup`: see OutputQueue.
    std::shared_ptr<Client> connect(std::function<void()> wakeup);
    /// One text message from `client`.
    void receive(const std::shared_ptr<Client>& client, std::string_view text);
    /// A binary message from `client` (clients send none): answered with bad_json.
    void receive_binary(const std::shared_ptr<Client>& client);
    /// `client`'s queue drained after a stall: its keyframes for these sessions.
    void catch_up(const std::shared_ptr<Client>& client,
                  const std::vector<protocol::SessionId>& sessions);
    /// The connection is gone: its subscriptions end (sessions left without subscribers stop
    /// refining and expire after the orphan timeout).
    void disconnect(const std::shared_ptr<Client>& client);

    /// Ends every session with `closed` (reason shutdown) and refuses new requests
    /// (`unavailable`); returns once those messages are queued or the drain timeout passed.
    void shutdown();
    bool shutting_down() const { return shutting_down_; }

    /// Expires sessions idle or orphaned too long at `now`. The housekeeper calls it; public for
    /// tests.
    void expire(Clock::time_point now);

    std::size_t session_count() const;
    std::shared_ptr<MeshSession> find(const protocol::SessionId& id) const;
    const ServerConfig& config() const { return config_; }
    Metrics& metrics() { return metrics_; }
    Logger& logger() { return logger_; }

  private:
    struct Request;
    void handle(Request& request, const protocol::Create& create);
    void handle(Request& request, const protocol::Update& update);
    void handle(Request& request, const protocol::Subscribe& subscribe);
    void handle(Request& request, const protocol::Unsubscribe& unsubscribe);
    void handle(Request& request, const protocol::Pause& pause);
    void handle(Request& request, const protocol::Resume& resume);
    void handle(Request& request, const protocol::Close& close);
    void handle(Request& request, const protocol::Resync& resync);
    void handle(Request& request, const protocol::Ping& ping);

    /// The session a request names, or nothing after replying unknown_session.
    std::shared_ptr<MeshSession> named_session(Request& request, const protocol::SessionId& id);
    std::shared_ptr<MeshSession> remove(const protocol::SessionId& id);
    void housekeeping();

    ServerConfig config_;
    Logger& logger_;
    Metrics& metrics_;
    VersionLimits version_limits_;
    protocol::ParseLimits parse_limits_;
    Watchdog watchdog_;
    WorkerPool pool_;
    std::atomic<bool> shutting_down_{false};
    std::atomic<std::uint64_t> next_client_id_{1};

    mutable std::mutex sessions_mutex_;
    std::map<protocol::SessionId, std::shared_ptr<MeshSession>> sessions_;

    std::mutex housekeeping_mutex_;
    std::condition_variable housekeeping_wake_;
    bool stopping_ = false;
    std::thread housekeeper_;
};

}  // namespace isomesh::server
