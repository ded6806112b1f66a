// A meshing session: one surface, its function versions and its refinement state, streamed to any
// number of subscribers.
//
// A session is an actor: requests (any thread) only leave notes in its inbox and schedule it on
// the worker pool; all computing, the refiner and the frames happen in run_slice(), which one
// worker at a time runs as a short turn:
//   1. take the inbox (a new function version, keyframe requests, pause, close);
//   2. start a new version: a new box or error measure means a new pipeline
//      (progressive/pipeline.h), whose first step makes a mesh within the first-mesh budget,
//      sent as a keyframe to every subscriber; new parameters or a new source go to
//      Pipeline::set_field, whose changes then stream as deltas;
//   3. send keyframes to late joiners and to connections that fell behind (at the sequence
//      number of the last delta, so the next delta follows them without a gap);
//   4. step the pipeline for one time slice (CPU time of the worker's thread) and gather the
//      changes; send them as one delta when the batch interval has passed, when enough triangles
//      changed, or on convergence. A step that replaced the whole mesh (phase 1 resolved more of
//      the topology) is sent as a keyframe instead.
// A new version raises the cancel flag, so stale work stops within one operation. Every subscriber
// receives the same frames (encoded once), so all end with identical meshes.
#pragma once

#include <atomic>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "progressive/pipeline.h"
#include "protocol/frame.h"
#include "protocol/messages.h"
#include "server/client.h"
#include "server/function_version.h"
#include "server/log.h"
#include "server/metrics.h"
#include "server/watchdog.h"
#include "server/wire_mesh.h"
#include "server/worker_pool.h"

namespace isomesh::server {

/// What every session of a server shares.
struct SessionSettings {
    Clock::duration slice = std::chrono::microseconds(2000);
    Clock::duration batch_interval = std::chrono::milliseconds(20);
    std::size_t batch_triangles = 2000;  ///< changes (triangles, vertices) that trigger a delta
    /// CPU time of a version's phase 1 beyond which it stops classifying and keeps the mesh it
    /// has (unresolved cells reported); a single step running this long fails the session.
    Clock::duration eval_timeout = std::chrono::seconds(10);
    /// CPU time of a session's first step: the first mesh leaves within it, whatever the function.
    Clock::duration first_mesh_budget = std::chrono::milliseconds(10);
    Clock::duration progress_interval = std::chrono::milliseconds(250);
    int position_bits = 14;
    /// Draco's encoder speed, 0 (smallest frames) to 10 (fastest); clients do not depend on it.
    int encoding_speed = protocol::MeshEncoding{}.encoding_speed;
    int phase1_min_depth = kRefinePhase1MinDepth;
};

struct SessionServices {
    WorkerPool& pool;
    Watchdog& watchdog;
    Metrics& metrics;
    Logger& logger;
    SessionSettings settings;
};

class MeshSession final : public Task, public std::enable_shared_from_this<MeshSession> {
  public:
    /// Called (from a worker) when the session ends by itself: evaluation timeout or failure.
    using EndHandler = std::function<void(const protocol::SessionId&)>;

    MeshSession(protocol::SessionId id, FunctionVersion first, SessionServices services,
                EndHandler on_end);
    ~MeshSession() override;

    const protocol::SessionId& id() const { return id_; }

    // ---- requests: any thread ----
    /// Adds a subscriber, whose queue must already expect this session's keyframe
    /// (OutputQueue::expect_keyframe); `reply` runs first (under the session's lock, so that the
    /// keyframe cannot overtake it), then the keyframe follows. False when the session has ended.
    bool subscribe(const std::shared_ptr<Client>& client, const std::function<void()>& reply);
    void unsubscribe(const Client& client);
    /// Sends `client` a fresh keyframe (resync, or catch-up after backpressure).
    void request_keyframe(const std::shared_ptr<Client>& client, bool catch_up);
    /// A new version, cancelling the work on the current one; replaces an update not yet started.
    /// Answers an `update`: the next version (or why there is none), built from the latest one
    /// under a lock so that concurrent updates all apply.
    /// `reply` gets the result before the new version can produce any frame, and may refuse a
    /// valid version by returning false (its record could not be stored): it is then not applied.
    void update(const protocol::Update& request, const VersionLimits& limits,
                const std::function<bool(const VersionResult&)>& reply);
    void set_paused(bool paused);
    /// Ends the session: subscribers get `closed` with `reason` after the frames already made.
    void close(protocol::Closed::Reason reason);

    /// The latest version requested (the base of the next update).
    FunctionVersion latest() const;
    std::size_t subscriber_count() const;
    /// Records a request naming this session (idle expiry).
    void touch();
    Clock::time_point last_request() const;
    /// Since when the session has had no subscriber, if it has none.
    std::optional<Clock::time_point> orphaned_since() const;

    // ---- the worker ----
    bool run_slice() override;

  private:
    struct KeyframeRequest {
        std::weak_ptr<Client> client;
        bool catch_up = false;
    };
    struct Inbox {
        std::optional<FunctionVersion> version;
        std::vector<KeyframeRequest> keyframes;
        std::vector<std::shared_ptr<Client>> subscribers;
        std::optional<protocol::Closed::Reason> closing;
        bool paused = false;
        bool finished = false;
    };
    enum class Start { started, superseded, failed };

    Inbox take_inbox();
    void schedule();
    Start start_version(FunctionVersion version, Inbox& inbox);
    Start restart(FunctionVersion& version, Inbox& inbox);
    bool refine_turn(Inbox& inbox);
    /// Sends the pipeline's whole mesh as a keyframe to every subscriber, as the next frame.
    void replace_mesh(Inbox& inbox, std::uint32_t version, bool converged);
    /// Stops phase 1 for good once it used the version's time limit.
    void limit_phase1(Clock::duration spent);
    void serve_keyframes(const std::vector<KeyframeRequest>& requests);
    void flush(const Inbox& inbox, bool converged);
    /// A `progress` or `converged` message with the mesh's statistics filled in.
    template <class Message>
    Message statistics() const;
    void send_progress(const Inbox& inbox);
    void send_converged(const Inbox& inbox);
    void observe_slice(Clock::time_point start);
    std::shared_ptr<const Bytes> encode_keyframe(std::uint16_t flags, std::uint32_t version) const;
    void broadcast(const std::vector<std::shared_ptr<Client>>& to,
                   const protocol::ServerMessage& message, bool droppable = false);
    /// Ends the session after a failure: `error` then `closed` to every subscriber.
    void fail(protocol::ErrorCode code, const std::string& message,
              const std::optional<protocol::RequestId>& request_id);
    void finish(protocol::Closed::Reason reason);
    std::vector<std::shared_ptr<Client>> live_subscribers();

    const protocol::SessionId id_;
    SessionServices services_;
    EndHandler on_end_;
    std::atomic<bool> cancel_{false};     // stop the current phase 1 or step
    std::atomic<bool> timed_out_{false};  // raised by the watchdog with cancel_

    // The inbox, guarded by mutex_.
    std::mutex update_mutex_;  // serializes update()
    mutable std::mutex mutex_;
    FunctionVersion latest_;
    std::optional<FunctionVersion> pending_version_;
    std::vector<std::weak_ptr<Client>> subscribers_;
    std::vector<KeyframeRequest> keyframe_requests_;
    std::optional<protocol::Closed::Reason> closing_;
    bool paused_ = false;
    bool finished_ = false;
    Clock::time_point last_request_;
    std::optional<Clock::time_point> orphaned_since_;

    // Worker state: touched only inside run_slice.
    FunctionVersion current_;
    std::unique_ptr<Pipeline> pipeline_;
    Clock::duration phase1_time_{};  // CPU time of the current version's phase 1 so far
    protocol::MeshEncoding encoding_;
    WireMesh wire_;
    DeltaBuilder pending_;
    std::size_t pending_changes_ = 0;  // triangles and vertices changed in pending_
    bool version_frame_due_ = false;   // a new version's first frame goes out as soon as it can
    // Incremented before each frame: unsigned wrap-around makes the first keyframe's number 0
    // (PROTOCOL.md 6.3).
    std::uint64_t sequence_ = std::numeric_limits<std::uint64_t>::max();
    bool converged_ = false;
    Clock::time_point last_flush_{};
    Clock::time_point last_progress_{};
    double first_mesh_ms_ = 0;
    RefineCounters counters_at_version_;
    std::optional<protocol::Converged> converged_message_;  // for late joiners
    std::size_t splits_since_progress_ = 0;
};

}  // namespace isomesh::server
