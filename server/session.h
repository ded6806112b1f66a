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
//
// A session has two ids: the control id (`created` returns it; every request) and the view id
// (read-only: subscribe, unsubscribe, resync). Each subscriber holds one of them and receives
// frames and messages naming the id it holds (a frame's copy for view holders differs only in
// its header's session id), so a view holder never learns the control id.
//
// Budgets, enforced at the edges of every turn: the CPU time of the session's turns (the worker
// thread's CPU clock) over the session's life, and its memory estimated from what it holds
// (server/resources.h); a session over either ends with `resource_limit`. A single step running
// longer than the evaluation limit in CPU time fails the session too (eval_timeout).
#pragma once

#include <array>
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
#include "server/first_mesh_cache.h"
#include "server/function_version.h"
#include "server/log.h"
#include "server/metrics.h"
#include "server/watchdog.h"
#include "server/wire_mesh.h"
#include "server/wire_mesh_v2.h"
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
    Clock::duration session_cpu = std::chrono::hours(1);  ///< CPU time over the session's life
    std::uint64_t session_memory_bytes = std::uint64_t{1280} << 20;
    Clock::duration progress_interval = std::chrono::milliseconds(250);
    /// A slider being dragged: a new version (of the same box and error measure) gets its moved
    /// frame at once, and the rest of its work (phase 1 again, refinement, the keyframe of its
    /// own mesh) waits until no newer version came for this long, since the next version would
    /// cancel that work (ROAM's camera in motion). Zero: never wait.
    Clock::duration rest_interval = std::chrono::milliseconds(100);
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
    /// New sessions' first meshes by request (first_mesh_cache.h); null: none kept.
    FirstMeshCache* first_meshes = nullptr;
};

/// A session's ids, and its serial number (the order of creation: what logs name, since the ids
/// are capabilities).
struct SessionIds {
    protocol::SessionId control;
    protocol::SessionId view;
    std::uint64_t serial = 0;
};

class MeshSession final : public Task, public std::enable_shared_from_this<MeshSession> {
  public:
    /// Called (from a worker) when the session ends by itself: evaluation timeout, a budget or a
    /// failure.
    using EndHandler = std::function<void(const protocol::SessionId&)>;

    MeshSession(SessionIds ids, FunctionVersion first, SessionServices services, EndHandler on_end);
    ~MeshSession() override;

    const protocol::SessionId& id() const { return id_; }
    const protocol::SessionId& view_id() const { return view_id_; }
    std::uint64_t serial() const { return serial_; }
    /// The id holders of `access` know the session by.
    const protocol::SessionId& id_for(protocol::Access access) const {
        return access == protocol::Access::view ? view_id_ : id_;
    }

    // ---- requests: any thread ----
    /// Adds a subscriber holding the id of `access`, whose queue must already expect that id's
    /// keyframe (OutputQueue::expect_keyframe); `reply` runs first (under the session's lock, so
    /// that the keyframe cannot overtake it), then the keyframe follows. False when the session
    /// has ended.
    bool subscribe(const std::shared_ptr<Client>& client, protocol::Access access,
                   const std::function<void()>& reply);
    void unsubscribe(const Client& client, protocol::Access access);
    /// Sends `client` a fresh keyframe (resync, or catch-up after backpressure).
    void request_keyframe(const std::shared_ptr<Client>& client, protocol::Access access,
                          bool catch_up);
    /// A new version, cancelling the work on the current one; replaces an update not yet started.
    /// Answers an `update` from `requester`: the next version (or why there is none), built from
    /// the latest one under a lock so that concurrent updates all apply. `reply` gets the result
    /// before the new version can produce any frame, and may refuse a valid version by returning
    /// false (its record could not be stored): it is then not applied. Once applied, every other
    /// subscriber gets `updated` without an id. An update that changes nothing makes no version:
    /// `reply` gets the latest (and its answer is ignored).
    void update(const protocol::Update& request, const VersionLimits& limits,
                const Client& requester, const std::function<bool(const VersionResult&)>& reply);
    void set_paused(bool paused);
    /// Ends the session at once, whatever its worker is doing (the work is cancelled): every
    /// subscriber gets `closed` with `reason` after the frames already queued, and nothing more.
    void close(protocol::Closed::Reason reason);

    /// The memory the session may come to hold: its latest triangle budget's projection.
    std::uint64_t reservation() const;
    /// The memory it holds now (estimated at the end of its last turn).
    std::uint64_t memory_estimate() const { return memory_estimate_; }
    /// The CPU time its turns have used.
    Clock::duration cpu_time() const { return Clock::duration(cpu_time_.load()); }

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
    struct Subscriber {
        std::weak_ptr<Client> client;
        protocol::Access access = protocol::Access::control;
    };
    struct LiveSubscriber {
        std::shared_ptr<Client> client;
        protocol::Access access = protocol::Access::control;
    };
    struct KeyframeRequest {
        std::weak_ptr<Client> client;
        bool catch_up = false;
        protocol::Access access = protocol::Access::control;
    };
    struct Inbox {
        std::optional<FunctionVersion> version;
        std::vector<KeyframeRequest> keyframes;
        std::vector<LiveSubscriber> subscribers;
        bool paused = false;
        bool finished = false;
    };
    /// A frame naming the control id and, made on first use, its copy naming the view id.
    struct FrameCopies {
        std::shared_ptr<const Bytes> control;
        std::shared_ptr<const Bytes> view;
    };
    /// How start_version went: started (on the current pipeline), restarted (a new pipeline, its
    /// first mesh sent), superseded (a newer version came first) or failed.
    enum class Start { started, restarted, superseded, failed };

    /// The protocol version a subscriber's connection speaks, as an index (0: version 1, 1: 2).
    static int protocol_index(const std::shared_ptr<Client>& client) {
        return client->protocol_version() == 2 ? 1 : 0;
    }
    Inbox take_inbox();
    void schedule();
    /// One turn (run_slice without the budgets around it).
    bool turn();
    /// After a turn: charges its CPU time and estimates the memory; false when a budget is spent.
    bool within_budgets(Clock::duration turn_cpu);
    void requeue_keyframes(std::vector<KeyframeRequest> requests);
    /// True while a new function is half applied (vertices partly moved): no frame may go out,
    /// since it would mix two surfaces.
    bool mid_change() const;
    /// The watchdog alarm for a phase 1 (the version's CPU-time limit).
    Watchdog::Guard arm_eval_limit();
    const std::shared_ptr<const Bytes>& frame_for(protocol::Access access,
                                                  FrameCopies& frame) const;
    /// Version-2 subscribers are there, and the version-2 mirror follows what they hold.
    bool prepare_v2(const std::vector<LiveSubscriber>& subscribers, bool replaced);
    void flush_v1(const Inbox& inbox, const WireDelta& content, const protocol::FrameInfo& info);
    void flush_v2(const Inbox& inbox, const MeshDelta& delta, const protocol::FrameInfo& info);
    void push_keyframes(const std::vector<LiveSubscriber>& to,
                        const std::shared_ptr<const Bytes>& frame, Clock::time_point created);
    /// Sends `message` (about this session) to each of `to`, naming the id each holds; with
    /// `sequence`, only to connections that have reached that frame (OutputQueue).
    template <class Message>
    void broadcast(const std::vector<LiveSubscriber>& to, Message message,
                   std::optional<std::uint64_t> sequence, bool droppable = false);
    /// Ends every subscription with `closed`; false when the session had ended already.
    bool end_subscriptions(protocol::Closed::Reason reason);
    Start start_version(FunctionVersion version, Inbox& inbox);
    Start restart(FunctionVersion& version, Inbox& inbox);
    std::unique_ptr<Pipeline> make_pipeline(const FunctionVersion& version);
    /// The pipeline's first step (the first mesh's budget, under the evaluation limit).
    PipelineStep first_step(Pipeline& pipeline);
    /// A new session whose request's first mesh is cached: sends it at once (the pipeline's own
    /// first step follows in the next turn, first_mesh_cache.h). False when none is cached.
    bool show_cached_first_mesh(Inbox& inbox, const FunctionVersion& version);
    /// Keeps the first mesh just shown for the next session asking for the same.
    void remember_first_mesh(const std::array<std::shared_ptr<const Bytes>, 2>& frames);
    /// After the pipeline's own first step, when a cached first mesh was shown: true when it is
    /// the mesh shown (else the caller shows its own).
    bool shown_mesh_confirmed();
    void record_first_mesh(const FunctionVersion& version);
    bool refine_turn(Inbox& inbox);
    /// One step of the pipeline for a turn's time slice.
    PipelineStep step_pipeline();
    /// The pipeline's own first step after a cached first mesh, its mesh sent if it differs.
    PipelineStep confirm_first_mesh(Inbox& inbox);
    /// Until when the work on `version` (about to replace current_) waits for its value to rest.
    Clock::time_point rest_deadline(const FunctionVersion& version) const;
    /// True when the current version's work waits for its value to rest (a turn is booked then).
    bool wait_for_rest();
    /// Sends the pipeline's whole mesh as a keyframe to every subscriber, as the next frame;
    /// `frames` (optional) receives the keyframe by protocol version.
    void replace_mesh(Inbox& inbox, std::uint32_t version, bool converged,
                      std::array<std::shared_ptr<const Bytes>, 2>* made = nullptr);
    /// Stops phase 1 for good once it used the version's time limit.
    void limit_phase1(Clock::duration spent);
    void serve_keyframes(const std::vector<KeyframeRequest>& requests);
    void flush(const Inbox& inbox, bool converged);
    /// Adds a step's changes to those of the next frame.
    void add_changes(MeshDelta delta);
    /// The net changes since the last frame; forgets them.
    MeshDelta take_changes();
    /// A `progress` or `converged` message with the mesh's statistics filled in.
    template <class Message>
    Message statistics() const;
    void send_progress(const Inbox& inbox);
    void send_converged(const Inbox& inbox);
    void observe_slice(Clock::time_point start);
    /// `protocol`: the protocol version of the frame (1: from wire_, 2: from wire_v2_; a mirror
    /// no client holds yet is numbered in Draco's decoded order, so its keyframe has no ids).
    std::shared_ptr<const Bytes> encode_keyframe(std::uint16_t flags, std::uint32_t version,
                                                 int protocol = 1);
    /// Ends the session after a failure: `error` then `closed` to every subscriber.
    void fail(protocol::ErrorCode code, const std::string& message,
              const std::optional<protocol::RequestId>& request_id);
    void finish(protocol::Closed::Reason reason);
    std::vector<LiveSubscriber> live_subscribers();
    std::vector<LiveSubscriber> live_subscribers_locked() const;

    const protocol::SessionId id_;
    const protocol::SessionId view_id_;
    const std::uint64_t serial_;
    SessionServices services_;
    /// The pool's idle workers, for phase 1's loops; their CPU time is charged to the session.
    ChargedHelpers helpers_{services_.pool};
    Clock::duration helpers_charged_{};  // of helpers_.cpu(), what within_budgets counted
    EndHandler on_end_;
    std::atomic<bool> cancel_{false};     // stop the current phase 1 or step
    std::atomic<bool> timed_out_{false};  // raised by the watchdog with cancel_
    std::atomic<bool> cpu_spent_{false};  // the session's CPU budget ran out during a turn
    std::atomic<Clock::rep> cpu_time_{0};
    std::atomic<bool> shown_{false};  // a first mesh went out: requests are no longer a new one's
    std::atomic<std::uint64_t> memory_estimate_{0};

    // The inbox, guarded by mutex_.
    std::mutex update_mutex_;  // serializes update()
    mutable std::mutex mutex_;
    FunctionVersion latest_;
    std::optional<FunctionVersion> pending_version_;
    std::vector<Subscriber> subscribers_;
    std::vector<KeyframeRequest> keyframe_requests_;
    bool paused_ = false;
    bool finished_ = false;
    Clock::time_point last_request_;
    std::optional<Clock::time_point> orphaned_since_;

    // Worker state: touched only inside run_slice.
    FunctionVersion current_;
    std::unique_ptr<Pipeline> pipeline_;
    Clock::duration phase1_time_{};  // CPU time of the current version's phase 1 so far
    bool phase1_settled_ = false;    // its classification stopped at the limit
    protocol::MeshEncoding encoding_;
    WireMesh wire_;
    WireMeshV2 wire_v2_;  // what version-2 subscribers hold
    // The changes since the last frame: one step's delta as the pipeline netted it (a frame of
    // one step, such as a slider's moved frame, is not netted again), or the deltas of several
    // steps netted together in pending_.
    std::optional<MeshDelta> pending_step_;
    DeltaBuilder pending_;
    bool pending_logged_ = false;      // pending_ holds changes
    std::size_t pending_changes_ = 0;  // triangles and vertices changed since the last frame
    bool version_frame_due_ = false;   // a new version's first frame goes out as soon as it can
    Clock::time_point rest_until_{};   // a dragged value's work waits until then (rest_interval)
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
    /// A keyframe shown while resolving: the next turn sends `progress` whatever the interval.
    bool progress_due_ = false;
    bool last_frame_converged_ = false;  // the last frame sent carries the converged flag
    // A new session's first mesh: the cache key of its request, and the cached mesh shown while
    // the pipeline's own first step has not run yet (first_mesh_cache.h).
    std::optional<std::string> first_mesh_key_;
    std::shared_ptr<const FirstMesh> unconfirmed_;
    std::uint32_t wire_version_ = 0;  // the function version of wire_'s content
};

}  // namespace isomesh::server
