// One simulated user of the server: a WebSocket connection holding one session at a time.
//
// On open it creates its mix entry's session and applies every frame to a MeshReplica (the
// protocol library's client state), recording time to first mesh and frame latencies. A session
// with a slider then sends `update`s at the configured rate, moving the parameter back and forth
// by 1/20 of its range per update; a session without one is held for a while after it converges,
// closed, and followed by the user's next entry of the mix. stop() closes everything.
#pragma once

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <optional>

#include "load_mix.h"
#include "load_stats.h"
#include "protocol/messages.h"
#include "protocol/replica.h"
#include "ws_client.h"

namespace isomesh::load {

struct UserSettings {
    double updates_per_s = 2;  ///< per slider session; 0: sliders stay still
    double hold_s = 2;         ///< a converged static session lives this long; <= 0: to the end
    int protocol_version = protocol::kMaxProtocolVersion;  ///< of every message and frame
    /// Each session's parameters and box moved at random by up to this share (load_mix.h
    /// jittered); 0: every session of an entry asks for the same mesh.
    double jitter = 0;
};

class VirtualUser : public std::enable_shared_from_this<VirtualUser> {
  public:
    using Clock = std::chrono::steady_clock;

    /// User `index` of `users`, taking its entries from `mix` (which must outlive it).
    /// `on_finished` runs once, on an I/O thread, when its connection has ended.
    VirtualUser(const Mix& mix, std::size_t index, std::size_t users, UserSettings settings,
                std::function<void()> on_finished);

    /// Connects through `loop` to `url` (a ws:// URL).
    void start(net::WsEventLoop& loop, const net::Url& url);
    /// Closes the session and the connection; any thread.
    void stop();

    /// Precondition: the event loop has stopped (no callback runs any more).
    const LoadStats& stats() const { return stats_; }
    /// Drops the connection. Precondition: the event loop has stopped.
    void release() { connection_.reset(); }

  private:
    void create_session();
    void on_text(const std::string& text);
    void on_frame(const net::WsMessage& message);
    void on_first_mesh();
    void on_converged(const protocol::Converged& converged);
    void on_error(const protocol::ErrorReply& error);
    void on_closed(const std::string& error);
    void schedule_update();
    void send_update();
    void recreate_later();
    void send(const protocol::ClientMessage& message);
    /// The mix entry of the current session, jittered.
    const MixEntry& entry() const { return entry_; }

    const Mix& mix_;
    const std::size_t index_;
    const std::size_t users_;
    const UserSettings settings_;
    std::function<void()> on_finished_;
    std::shared_ptr<net::WsConnection> connection_;

    // Everything below is touched only on the connection's strand.
    std::int64_t next_request_id_ = 1;
    std::size_t round_ = 0;  ///< how many sessions this user has created before the current one
    MixEntry entry_;
    std::optional<protocol::SessionId> session_;
    std::int64_t create_id_ = 0;
    Clock::time_point create_sent_{};
    bool have_first_mesh_ = false;
    protocol::MeshReplica replica_;
    double slider_value_ = 0;
    double slider_step_ = 0;
    std::map<std::int64_t, Clock::time_point> updates_in_flight_;  ///< by request id
    std::map<std::uint32_t, Clock::time_point> versions_awaited_;  ///< by function version
    bool stopping_ = false;
    LoadStats stats_;
};

}  // namespace isomesh::load
