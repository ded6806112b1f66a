#include "server/session.h"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <utility>

#include "server/resources.h"

namespace isomesh::server {
namespace {

using protocol::ErrorCode;

double milliseconds_between(Clock::time_point from, Clock::time_point to) {
    return 1000.0 * seconds_between(from, to);
}

std::string timeout_message(Clock::duration limit) {
    const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(limit).count();
    return "evaluating the function exceeded the time limit of " + std::to_string(ms) + " ms";
}

}  // namespace

MeshSession::MeshSession(SessionIds ids, FunctionVersion first, SessionServices services,
                         EndHandler on_end)
    : id_(ids.control),
      view_id_(ids.view),
      serial_(ids.serial),
      services_(services),
      on_end_(std::move(on_end)),
      latest_(first),
      pending_version_(std::move(first)),
      last_request_(Clock::now()),
      orphaned_since_(Clock::now()) {
    services_.metrics.sessions.add(1);
    services_.metrics.sessions_created.add();
}

MeshSession::~MeshSession() {
    services_.metrics.sessions.add(-1);
    services_.metrics.subscriptions.add(-static_cast<std::int64_t>(subscribers_.size()));
}

// ---- requests ---------------------------------------------------------------------------------

bool MeshSession::subscribe(const std::shared_ptr<Client>& client, protocol::Access access,
                            const std::function<void()>& reply) {
    {
        std::lock_guard lock(mutex_);
        if (finished_) return false;
        if (reply) reply();
        const bool known = std::any_of(
            subscribers_.begin(), subscribers_.end(),
            [&](const Subscriber& s) { return s.access == access && s.client.lock() == client; });
        if (!known) {
            subscribers_.push_back({client, access});
            services_.metrics.subscriptions.add(1);
        }
        orphaned_since_.reset();
        keyframe_requests_.push_back({client, false, access});
    }
    schedule();
    return true;
}

void MeshSession::unsubscribe(const Client& client, protocol::Access access) {
    std::lock_guard lock(mutex_);
    auto gone = std::remove_if(subscribers_.begin(), subscribers_.end(), [&](const Subscriber& s) {
        auto subscriber = s.client.lock();
        return !subscriber || (subscriber.get() == &client && s.access == access);
    });
    services_.metrics.subscriptions.add(-static_cast<std::int64_t>(subscribers_.end() - gone));
    subscribers_.erase(gone, subscribers_.end());
    if (subscribers_.empty() && !orphaned_since_) orphaned_since_ = Clock::now();
}

void MeshSession::request_keyframe(const std::shared_ptr<Client>& client, protocol::Access access,
                                   bool catch_up) {
    {
        std::lock_guard lock(mutex_);
        if (finished_) return;
        keyframe_requests_.push_back({client, catch_up, access});
    }
    schedule();
}

void MeshSession::update(const protocol::Update& request, const VersionLimits& limits,
                         const Client& requester,
                         const std::function<bool(const VersionResult&)>& reply) {
    std::lock_guard serial(update_mutex_);
    const FunctionVersion current = latest();
    VersionResult next = next_version(current, request, limits);
    if (next && changes_nothing(current, next.value())) {
        reply(current);  // nothing to store or apply: the reply names the latest version
        return;
    }
    if (!reply(next) || !next) return;
    std::vector<LiveSubscriber> others = live_subscribers();
    std::erase_if(others, [&](const LiveSubscriber& s) {
        return s.client.get() == &requester && s.access == protocol::Access::control;
    });
    broadcast(others, protocol::Updated{std::nullopt, id_, next.value().state}, std::nullopt);
    {
        std::lock_guard lock(mutex_);
        latest_ = next.value();
        pending_version_ = std::move(next).value();
        cancel_ = true;
    }
    schedule();
}

void MeshSession::set_paused(bool paused) {
    {
        std::lock_guard lock(mutex_);
        paused_ = paused;
    }
    if (!paused) schedule();
}

void MeshSession::close(protocol::Closed::Reason reason) {
    cancel_ = true;
    end_subscriptions(reason);
}

std::uint64_t MeshSession::reservation() const {
    std::lock_guard lock(mutex_);
    return SessionMemory::projected(*latest_.state.constraints.triangles);
}

FunctionVersion MeshSession::latest() const {
    std::lock_guard lock(mutex_);
    return latest_;
}

std::size_t MeshSession::subscriber_count() const {
    std::lock_guard lock(mutex_);
    return live_subscribers_locked().size();
}

void MeshSession::touch() {
    std::lock_guard lock(mutex_);
    last_request_ = Clock::now();
}

Clock::time_point MeshSession::last_request() const {
    std::lock_guard lock(mutex_);
    return last_request_;
}

std::optional<Clock::time_point> MeshSession::orphaned_since() const {
    std::lock_guard lock(mutex_);
    return orphaned_since_;
}

void MeshSession::schedule() {
    // A request waits on this turn; until the first mesh, it is a new session's (worker_pool.h).
    services_.pool.schedule(shared_from_this(), shown_ ? Lane::urgent : Lane::new_session);
}

// ---- the worker -------------------------------------------------------------------------------

MeshSession::Inbox MeshSession::take_inbox() {
    std::lock_guard lock(mutex_);
    Inbox inbox;
    inbox.finished = finished_;
    inbox.paused = paused_;
    if (!paused_ && pending_version_) {
        inbox.version = std::move(*pending_version_);
        pending_version_.reset();
        cancel_ = false;
        timed_out_ = false;
    }
    inbox.keyframes = std::move(keyframe_requests_);
    keyframe_requests_.clear();
    inbox.subscribers = live_subscribers_locked();
    return inbox;
}

bool MeshSession::run_slice() {
    const Clock::duration cpu_start = thread_cpu_time();
    bool more = false;
    {
        // The session's CPU budget also bounds a single turn, e.g. a phase 1 that runs long.
        const auto left = services_.settings.session_cpu - cpu_time();
        auto guard =
            services_.watchdog.arm(std::max(left, Clock::duration::zero()), cancel_, cpu_spent_);
        more = turn();
    }
    // The workers that helped phase 1 worked for this session too.
    const Clock::duration helped = helpers_.cpu() - helpers_charged_;
    helpers_charged_ += helped;
    return within_budgets(thread_cpu_time() - cpu_start + helped) && more;
}

bool MeshSession::within_budgets(Clock::duration turn_cpu) {
    cpu_time_ += turn_cpu.count();
    services_.metrics.session_cpu_us.add(static_cast<std::uint64_t>(
        std::chrono::duration_cast<std::chrono::microseconds>(turn_cpu).count()));
    std::uint64_t queued = 0;
    const std::vector<LiveSubscriber> subscribers = live_subscribers();
    for (const LiveSubscriber& s : subscribers)
        queued += s.client->queue().session_bytes(id_for(s.access));
    memory_estimate_ = SessionMemory::estimate(wire_.triangle_count(), queued);
    {
        std::lock_guard lock(mutex_);
        if (finished_) return false;
    }
    const auto mib = [](std::uint64_t bytes) { return std::to_string(bytes >> 20) + " MiB"; };
    if (memory_estimate_ > services_.settings.session_memory_bytes) {
        fail(ErrorCode::resource_limit,
             "the session holds about " + mib(memory_estimate_) + ", more than its budget of " +
                 mib(services_.settings.session_memory_bytes),
             current_.request_id);
        return false;
    }
    if (cpu_spent_ || cpu_time() >= services_.settings.session_cpu) {
        const auto seconds = [](Clock::duration d) {
            return std::to_string(std::chrono::duration_cast<std::chrono::seconds>(d).count());
        };
        fail(ErrorCode::resource_limit,
             "the session used its CPU-time budget of " + seconds(services_.settings.session_cpu) +
                 " s",
             current_.request_id);
        return false;
    }
    return true;
}

void MeshSession::requeue_keyframes(std::vector<KeyframeRequest> requests) {
    std::lock_guard lock(mutex_);
    keyframe_requests_.insert(keyframe_requests_.begin(), requests.begin(), requests.end());
}

bool MeshSession::mid_change() const {
    return pipeline_ && pipeline_->field_change_pending();
}

Watchdog::Guard MeshSession::arm_eval_limit() {
    return services_.watchdog.arm(services_.settings.eval_timeout, cancel_, timed_out_);
}

bool MeshSession::turn() {
    const Clock::time_point start = Clock::now();
    Inbox inbox = take_inbox();
    if (inbox.finished) return false;
    try {
        Start started = Start::started;
        if (inbox.version) {
            last_frame_converged_ = false;  // a new version's frames start unflagged
            started = start_version(std::move(*inbox.version), inbox);
            if (started == Start::failed) return false;
            if (started == Start::superseded) {
                // Keyframes asked for are served by a later turn (a lost request would leave a
                // subscriber waiting for a keyframe forever).
                requeue_keyframes(std::move(inbox.keyframes));
                return true;
            }
        }
        if (!pipeline_) return false;
        serve_keyframes(inbox.keyframes);
        if (inbox.paused || inbox.subscribers.empty() || converged_) {
            if (!mid_change()) flush(inbox, converged_);
            return false;
        }
        if (started == Start::restarted) {
            // The first mesh of a new pipeline left in an urgent turn; its refinement goes on in
            // round-robin turns, so that the next new session's first mesh does not wait for it.
            // (A cached first mesh was followed by its progress already.)
            if (pipeline_->started()) send_progress(inbox);
            return true;
        }
        const bool more = refine_turn(inbox);
        observe_slice(start);
        return more;
    } catch (const std::exception& e) {
        fail(ErrorCode::internal, e.what(), current_.request_id);
        return false;
    }
}

void MeshSession::observe_slice(Clock::time_point start) {
    services_.metrics.slice_seconds.observe(seconds_between(start, Clock::now()));
}

MeshSession::Start MeshSession::start_version(FunctionVersion version, Inbox& inbox) {
    const bool same_pipeline = pipeline_ && version.state.box == current_.state.box &&
                               version.error_measure->name() == current_.error_measure->name();
    if (same_pipeline && !pipeline_->started()) {
        // A cached first mesh not yet confirmed: the new version builds on the pipeline's own
        // (a slider's first update then moves its vertices, as without the cache).
        confirm_first_mesh(inbox);
        if (timed_out_) {
            fail(ErrorCode::eval_timeout, timeout_message(services_.settings.eval_timeout),
                 current_.request_id);
            return Start::failed;
        }
    }
    // The old version's last changes, under its own version number; those of a version still
    // half applied (vertices partly moved) wait for the new version's first frame instead.
    if (!mid_change()) flush(inbox, false);
    // A pipeline that has not made its first step (a cached first mesh shown) starts afresh.
    const bool restart_needed = !pipeline_ || !pipeline_->started() ||
                                version.state.box != current_.state.box ||
                                version.error_measure->name() != current_.error_measure->name();
    if (restart_needed) {
        const Start started = restart(version, inbox);
        if (started != Start::restarted) return started;
    } else {
        // The vertices move onto the new surface in the next steps, while phase 1 runs again for
        // the new function (progressive/pipeline.h): nothing long happens here.
        if (version.field != current_.field) pipeline_->set_field(version.field);
        pipeline_->set_constraint(version.constraint);
        version_frame_due_ = true;
        first_mesh_ms_ = 0;
    }
    rest_until_ = restart_needed ? Clock::time_point{} : rest_deadline(version);
    current_ = std::move(version);
    converged_ = false;
    converged_message_.reset();
    counters_at_version_ = pipeline_->started() ? pipeline_->counters() : RefineCounters{};
    phase1_time_ = {};
    phase1_settled_ = false;
    last_progress_ = Clock::now();
    splits_since_progress_ = 0;
    return restart_needed ? Start::restarted : Start::started;
}

std::unique_ptr<Pipeline> MeshSession::make_pipeline(const FunctionVersion& version) {
    PipelineSettings settings;
    settings.phase1.box = version.box;
    settings.phase1.min_depth = services_.settings.phase1_min_depth;
    // Phase 1's loops run on this worker and on the pool's idle ones (worker_pool.h: a busy server
    // gives each session one core); the mesh is the same whatever the number of helpers.
    settings.phase1.threads = static_cast<int>(std::max(1u, helpers_.threads()));
    settings.phase1.helpers = &helpers_;
    settings.refine.error_measure = version.error_measure;
    settings.refine.constraint = version.constraint;
    return std::make_unique<Pipeline>(version.field, std::move(settings));
}

PipelineStep MeshSession::first_step(Pipeline& pipeline) {
    const auto budget_us =
        std::chrono::duration_cast<std::chrono::microseconds>(services_.settings.first_mesh_budget)
            .count();
    // The step stops at its budget; the watchdog only catches a runaway evaluation.
    auto guard = arm_eval_limit();
    return pipeline.step(WorkBudget(budget_us, WorkBudget::thread_cpu_clock(), &cancel_));
}

MeshSession::Start MeshSession::restart(FunctionVersion& version, Inbox& inbox) {
    unconfirmed_.reset();
    first_mesh_key_.reset();
    if (!shown_ && services_.first_meshes && show_cached_first_mesh(inbox, version))
        return Start::restarted;
    auto pipeline = make_pipeline(version);
    const PipelineStep first = first_step(*pipeline);
    if (!pipeline->started()) {
        if (!timed_out_) return Start::superseded;
        fail(ErrorCode::eval_timeout, timeout_message(services_.settings.eval_timeout),
             version.request_id);
        return Start::failed;
    }
    pipeline_ = std::move(pipeline);
    encoding_.grid =
        protocol::QuantizationGrid::for_box(version.state.box, services_.settings.position_bits);
    encoding_.encoding_speed = services_.settings.encoding_speed;
    converged_ = first.converged;
    std::array<std::shared_ptr<const Bytes>, 2> frames;
    replace_mesh(inbox, version.state.version, first.converged, &frames);
    if (first_mesh_key_ && !first.converged) remember_first_mesh(frames);
    first_mesh_key_.reset();
    record_first_mesh(version);
    return Start::restarted;
}

void MeshSession::record_first_mesh(const FunctionVersion& version) {
    shown_ = true;
    const Clock::time_point now = Clock::now();
    first_mesh_ms_ = milliseconds_between(version.requested, now);
    services_.metrics.first_mesh_seconds.observe(seconds_between(version.requested, now));
    services_.logger.debug("first_mesh", {{"session", serial_},
                                          {"version", version.state.version},
                                          {"triangles", wire_.triangle_count()},
                                          {"latency_ms", first_mesh_ms_},
                                          {"cached", unconfirmed_ != nullptr}});
}

bool MeshSession::show_cached_first_mesh(Inbox& inbox, const FunctionVersion& version) {
    unsigned protocols = 0;
    for (const LiveSubscriber& s : inbox.subscribers) protocols |= 1u << protocol_index(s.client);
    if (protocols == 0) return false;
    first_mesh_key_ = first_mesh_key(version, protocols);
    if (!first_mesh_key_) return false;
    std::shared_ptr<const FirstMesh> first = services_.first_meshes->find(*first_mesh_key_);
    if (!first) {
        services_.metrics.first_mesh_cache_misses.add();
        // Kept the second time it is asked for (first_mesh_cache.h).
        if (!services_.first_meshes->seen_before(*first_mesh_key_)) first_mesh_key_.reset();
        return false;
    }
    services_.metrics.first_mesh_cache_hits.add();
    first_mesh_key_.reset();
    // The pipeline makes its first step in the next turn (refine_turn), to confirm this mesh.
    pipeline_ = make_pipeline(version);
    unconfirmed_ = first;
    encoding_.grid =
        protocol::QuantizationGrid::for_box(version.state.box, services_.settings.position_bits);
    encoding_.encoding_speed = services_.settings.encoding_speed;
    converged_ = false;
    wire_ = first->wire;
    wire_v2_ = first->wire_v2;
    take_changes();
    ++sequence_;
    const Clock::time_point now = Clock::now();
    const std::uint64_t timestamp = unix_time_us();
    std::array<std::shared_ptr<const Bytes>, 2> frames;
    for (const LiveSubscriber& s : inbox.subscribers) {
        const int index = protocol_index(s.client);
        if (!frames[index])
            frames[index] = std::make_shared<const Bytes>(
                protocol::with_session(*first->keyframes[index], id_, timestamp));
        push_keyframes({s}, frames[index], now);
    }
    wire_version_ = version.state.version;
    last_frame_converged_ = false;
    inbox.keyframes.clear();
    last_flush_ = now;
    if (first->progress.resolving) broadcast(inbox.subscribers, first->progress, sequence_, true);
    record_first_mesh(version);
    return true;
}

void MeshSession::remember_first_mesh(const std::array<std::shared_ptr<const Bytes>, 2>& frames) {
    auto first = std::make_shared<FirstMesh>();
    first->mesh = pipeline_->mesh();
    first->wire = wire_;
    first->wire_v2 = wire_v2_;
    first->keyframes = frames;
    first->progress = statistics<protocol::Progress>();
    first->progress.resolving = pipeline_->status().resolving;
    measure(*first, *first_mesh_key_);
    services_.first_meshes->insert(*first_mesh_key_, std::move(first));
    services_.metrics.first_mesh_cache_entries.set(
        static_cast<std::int64_t>(services_.first_meshes->entries()));
    services_.metrics.first_mesh_cache_bytes.set(
        static_cast<std::int64_t>(services_.first_meshes->bytes()));
}

bool MeshSession::shown_mesh_confirmed() {
    const std::shared_ptr<const FirstMesh> shown = std::exchange(unconfirmed_, nullptr);
    if (!shown) return false;
    const RefinedMesh own = pipeline_->mesh();
    const RefinedMesh& cached = shown->mesh;
    const bool same =
        own.triangle_ids == cached.triangle_ids && own.vertex_ids == cached.vertex_ids &&
        own.mesh.triangles == cached.mesh.triangles &&
        own.mesh.positions == cached.mesh.positions && own.mesh.normals == cached.mesh.normals;
    if (!same) services_.metrics.first_mesh_cache_mismatches.add();
    return same;
}

void MeshSession::limit_phase1(Clock::duration spent) {
    if (!pipeline_->status().resolving || phase1_settled_) return;
    phase1_time_ += spent;
    if (phase1_time_ < services_.settings.eval_timeout) return;
    // Once: what is left (the final mesh, its simplification) is made over the next turns.
    phase1_settled_ = true;
    // Slow to resolve, not broken: the mesh shown so far stays, its unresolved cells reported.
    pipeline_->settle();
    services_.logger.info("phase1_limited",
                          {{"version", current_.state.version},
                           {"unresolved_cells", pipeline_->status().unresolved_cells}});
}

Clock::time_point MeshSession::rest_deadline(const FunctionVersion& version) const {
    // Any new version may be the first of a slider's drag (the next update tells, too late: the
    // first update of bench/slider.mjs's drag went on to phase 1, the refinement and the 64 kB
    // keyframe of its own mesh, and held up the second's moved frame by 100 ms or more).
    return version.requested + services_.settings.rest_interval;
}

bool MeshSession::wait_for_rest() {
    if (mid_change() || version_frame_due_ || Clock::now() >= rest_until_) return false;
    services_.pool.schedule_at(shared_from_this(), rest_until_);
    return true;
}

PipelineStep MeshSession::step_pipeline() {
    // A new version's vertices on their way to its surface: the user waits for that frame, so the
    // turn may take the first mesh's budget (the pipeline's step ends once they are all moved).
    const Clock::duration slice =
        mid_change() ? services_.settings.first_mesh_budget : services_.settings.slice;
    const auto slice_us = std::chrono::duration_cast<std::chrono::microseconds>(slice).count();
    const WorkBudget budget(slice_us, WorkBudget::thread_cpu_clock(), &cancel_);
    PipelineStep step;
    const Clock::duration helped_before = helpers_.cpu();
    {
        // The step stops at its budget; the watchdog only catches a runaway evaluation.
        auto guard = arm_eval_limit();
        step = pipeline_->step(budget);
    }
    // Phase 1's CPU time: this worker's (the budget's clock) and its helpers'.
    limit_phase1(std::chrono::microseconds(budget.elapsed()) + helpers_.cpu() - helped_before);
    return step;
}

PipelineStep MeshSession::confirm_first_mesh(Inbox& inbox) {
    PipelineStep step = first_step(*pipeline_);
    if (pipeline_->started() && !shown_mesh_confirmed())
        replace_mesh(inbox, current_.state.version, step.converged && !step.cancelled);
    return step;
}

bool MeshSession::refine_turn(Inbox& inbox) {
    if (wait_for_rest()) return false;
    // After a cached first mesh, the pipeline's own first step (confirm_first_mesh).
    const bool first = !pipeline_->started();
    PipelineStep step = first ? confirm_first_mesh(inbox) : step_pipeline();
    if (timed_out_) {
        fail(ErrorCode::eval_timeout, timeout_message(services_.settings.eval_timeout),
             current_.request_id);
        return false;
    }
    services_.metrics.splits.add(step.splits);
    services_.metrics.merges.add(step.merges);
    splits_since_progress_ += step.splits;
    // The step's changes are the mesh's, cancelled or not: the next frames build on them.
    if (first) {
        // confirm_first_mesh sent what was needed.
    } else if (step.restarted) {
        // Phase 1 resolved more of the topology: the whole mesh is replaced.
        replace_mesh(inbox, current_.state.version, step.converged && !step.cancelled);
    } else {
        add_changes(std::move(step.delta));
    }
    if (step.cancelled) return true;  // a new version or a close waits in the inbox
    converged_ = step.converged;
    if (pipeline_->field_change_pending()) {
        // A new version is half applied: a frame now would mix surfaces. The user is waiting for
        // it, so the next turn stays in the urgent lane (worker_pool.h).
        schedule();
    } else if (converged_ || std::exchange(version_frame_due_, false) ||
               pending_changes_ >= services_.settings.batch_triangles ||
               Clock::now() - last_flush_ >= services_.settings.batch_interval) {
        flush(inbox, converged_);
    }
    if (converged_) {
        send_converged(inbox);
    } else {
        send_progress(inbox);
    }
    return !converged_;
}

template <class Message>
Message MeshSession::statistics() const {
    const MeshStats stats = pipeline_->stats();
    const PipelineStatus& status = pipeline_->status();
    Message message;
    message.session = id_;
    message.version = current_.state.version;
    message.sequence = sequence_;
    message.triangles = stats.triangles;
    message.error_max = stats.max_error;
    message.error_total = stats.total_error;
    message.certified = status.certified;
    message.unresolved_cells = status.unresolved_cells;
    return message;
}

void MeshSession::send_progress(const Inbox& inbox) {
    const Clock::time_point now = Clock::now();
    if (!progress_due_ && now - last_progress_ < services_.settings.progress_interval) return;
    progress_due_ = false;
    auto progress = statistics<protocol::Progress>();
    const double seconds = seconds_between(last_progress_, now);  // 0 right after a first mesh
    progress.splits_per_second = seconds > 0 ? splits_since_progress_ / seconds : 0;
    progress.resolving = pipeline_->status().resolving;
    broadcast(inbox.subscribers, progress, progress.sequence, true);
    last_progress_ = now;
    splits_since_progress_ = 0;
}

void MeshSession::send_converged(const Inbox& inbox) {
    const RefineCounters& counters = pipeline_->counters();
    const PipelineStatus& status = pipeline_->status();
    auto message = statistics<protocol::Converged>();
    message.outcome = status.region            ? protocol::Outcome::region_not_surface
                      : message.triangles == 0 ? protocol::Outcome::no_surface
                                               : protocol::Outcome::surface;
    message.budget_unreachable = status.budget_unreachable;
    message.splits = counters.splits - counters_at_version_.splits;
    message.merges = counters.merges - counters_at_version_.merges;
    message.first_mesh_ms = first_mesh_ms_;
    message.total_ms = milliseconds_between(current_.requested, Clock::now());
    broadcast(inbox.subscribers, message, message.sequence);
    converged_message_ = message;
    services_.logger.debug("converged", {{"session", serial_},
                                         {"version", message.version},
                                         {"triangles", message.triangles},
                                         {"total_ms", message.total_ms}});
}

template <class Message>
void MeshSession::broadcast(const std::vector<LiveSubscriber>& to, Message message,
                            std::optional<std::uint64_t> sequence, bool droppable) {
    // Naming the control id or the view id, in protocol version 1 or 2.
    std::shared_ptr<const std::string> texts[2][2];
    for (const LiveSubscriber& s : to) {
        const int version = protocol_index(s.client);
        auto& text = texts[version][s.access == protocol::Access::view ? 1 : 0];
        if (!text) {
            message.session = id_for(s.access);
            if constexpr (requires { message.access; }) {  // created, updated, subscribed
                message.access = s.access;
                message.view = s.access == protocol::Access::control
                                   ? std::optional<protocol::SessionId>(view_id_)
                                   : std::nullopt;
            }
            text = std::make_shared<const std::string>(
                protocol::serialize(protocol::ServerMessage(message), version + 1));
        }
        s.client->queue().push_session_text(id_for(s.access), text, sequence, droppable);
    }
}

// serve_keyframes (session_frames.cpp) sends a late joiner the `converged` message.
template void MeshSession::broadcast(const std::vector<LiveSubscriber>&, protocol::Converged,
                                     std::optional<std::uint64_t>, bool);

void MeshSession::fail(ErrorCode code, const std::string& message,
                       const std::optional<protocol::RequestId>& request_id) {
    services_.logger.warn(
        "session_failed",
        {{"session", serial_}, {"code", protocol::to_string(code)}, {"message", message}});
    services_.metrics.errors[static_cast<int>(code)].add();
    protocol::ErrorReply error;
    error.id = request_id;
    error.session = id_;
    error.code = code;
    error.message = message;
    broadcast(live_subscribers(), error, std::nullopt);
    // Out of the registry (and the store) before `closed` leaves: a request made on reading it
    // finds the session gone.
    if (on_end_) on_end_(id_);
    finish(protocol::Closed::Reason::error);
}

void MeshSession::finish(protocol::Closed::Reason reason) {
    end_subscriptions(reason);
    pipeline_.reset();
    wire_ = WireMesh();
}

bool MeshSession::end_subscriptions(protocol::Closed::Reason reason) {
    std::vector<LiveSubscriber> subscribers;
    {
        std::lock_guard lock(mutex_);
        if (finished_) return false;
        finished_ = true;
        subscribers = live_subscribers_locked();
        services_.metrics.subscriptions.add(-static_cast<std::int64_t>(subscribers_.size()));
        subscribers_.clear();
        keyframe_requests_.clear();
        pending_version_.reset();
    }
    for (const LiveSubscriber& s : subscribers) {
        const protocol::SessionId& id = id_for(s.access);
        s.client->remove_subscription(id);
        s.client->queue().forget(id, false);  // frames already queued still go out
        s.client->send(protocol::Closed{id, reason});
    }
    return true;
}

std::vector<MeshSession::LiveSubscriber> MeshSession::live_subscribers() {
    std::lock_guard lock(mutex_);
    return live_subscribers_locked();
}

std::vector<MeshSession::LiveSubscriber> MeshSession::live_subscribers_locked() const {
    std::vector<LiveSubscriber> out;
    for (const Subscriber& s : subscribers_) {
        if (auto client = s.client.lock()) out.push_back({std::move(client), s.access});
    }
    return out;
}

}  // namespace isomesh::server
