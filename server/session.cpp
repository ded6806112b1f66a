#include "server/session.h"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <utility>

#include "polygonize/polygonizer.h"

namespace isomesh::server {
namespace {

using protocol::ErrorCode;

/// Adds a refiner step's changes to the batch being gathered for the next delta.
void gather(DeltaBuilder& batch, const MeshDelta& delta) {
    for (std::uint32_t id : delta.removed_triangles) batch.remove_triangle(id);
    for (std::uint32_t id : delta.removed_vertices) batch.remove_vertex(id);
    for (const DeltaVertex& v : delta.added_vertices) batch.add_vertex(v);
    for (const DeltaVertex& v : delta.moved_vertices) batch.move_vertex(v);
    for (const DeltaTriangle& t : delta.added_triangles) batch.add_triangle(t);
}

double milliseconds_between(Clock::time_point from, Clock::time_point to) {
    return 1000.0 * seconds_between(from, to);
}

std::string timeout_message(Clock::duration limit) {
    const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(limit).count();
    return "evaluating the function exceeded the time limit of " + std::to_string(ms) + " ms";
}

}  // namespace

MeshSession::MeshSession(protocol::SessionId id, FunctionVersion first, SessionServices services,
                         EndHandler on_end)
    : id_(id),
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

bool MeshSession::subscribe(const std::shared_ptr<Client>& client,
                            const std::function<void()>& reply) {
    {
        std::lock_guard lock(mutex_);
        if (finished_ || closing_) return false;
        if (reply) reply();
        const bool known = std::any_of(subscribers_.begin(), subscribers_.end(),
                                       [&](const auto& s) { return s.lock() == client; });
        if (!known) {
            subscribers_.push_back(client);
            services_.metrics.subscriptions.add(1);
        }
        orphaned_since_.reset();
        keyframe_requests_.push_back({client, false});
    }
    schedule();
    return true;
}

void MeshSession::unsubscribe(const Client& client) {
    std::lock_guard lock(mutex_);
    auto gone = std::remove_if(subscribers_.begin(), subscribers_.end(), [&](const auto& s) {
        auto subscriber = s.lock();
        return !subscriber || subscriber.get() == &client;
    });
    services_.metrics.subscriptions.add(-static_cast<std::int64_t>(subscribers_.end() - gone));
    subscribers_.erase(gone, subscribers_.end());
    if (subscribers_.empty() && !orphaned_since_) orphaned_since_ = Clock::now();
}

void MeshSession::request_keyframe(const std::shared_ptr<Client>& client, bool catch_up) {
    {
        std::lock_guard lock(mutex_);
        if (finished_) return;
        keyframe_requests_.push_back({client, catch_up});
    }
    schedule();
}

void MeshSession::update(const protocol::Update& request, const VersionLimits& limits,
                         const std::function<bool(const VersionResult&)>& reply) {
    std::lock_guard serial(update_mutex_);
    VersionResult next = next_version(latest(), request, limits);
    if (!reply(next) || !next) return;
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
    {
        std::lock_guard lock(mutex_);
        if (finished_ || closing_) return;
        closing_ = reason;
        cancel_ = true;
    }
    schedule();
}

FunctionVersion MeshSession::latest() const {
    std::lock_guard lock(mutex_);
    return latest_;
}

std::size_t MeshSession::subscriber_count() const {
    std::lock_guard lock(mutex_);
    return static_cast<std::size_t>(std::count_if(subscribers_.begin(), subscribers_.end(),
                                                  [](const auto& s) { return !s.expired(); }));
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
    services_.pool.schedule(shared_from_this(), Lane::urgent);  // a request waits on this turn
}

// ---- the worker -------------------------------------------------------------------------------

MeshSession::Inbox MeshSession::take_inbox() {
    std::lock_guard lock(mutex_);
    Inbox inbox;
    inbox.finished = finished_;
    inbox.closing = closing_;
    inbox.paused = paused_;
    if (!paused_ && pending_version_) {
        inbox.version = std::move(*pending_version_);
        pending_version_.reset();
        cancel_ = false;
        timed_out_ = false;
    }
    inbox.keyframes = std::move(keyframe_requests_);
    keyframe_requests_.clear();
    for (const auto& weak : subscribers_) {
        if (auto client = weak.lock()) inbox.subscribers.push_back(std::move(client));
    }
    return inbox;
}

bool MeshSession::run_slice() {
    const Clock::time_point start = Clock::now();
    Inbox inbox = take_inbox();
    if (inbox.finished) return false;
    if (inbox.closing) {
        finish(*inbox.closing);
        return false;
    }
    try {
        if (inbox.version) {
            const Start started = start_version(std::move(*inbox.version), inbox);
            if (started == Start::failed) return false;
            if (started == Start::superseded) return true;
        }
        if (!pipeline_) return false;
        serve_keyframes(inbox.keyframes);
        if (inbox.paused || inbox.subscribers.empty() || converged_) {
            flush(inbox, converged_);
            return false;
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
    flush(inbox, false);  // the old version's last changes, under its own version number
    const bool restart_needed = !pipeline_ || version.state.box != current_.state.box ||
                                version.error_measure->name() != current_.error_measure->name();
    if (restart_needed) {
        const Start started = restart(version, inbox);
        if (started != Start::started) return started;
    } else {
        // The vertices move onto the new surface in the next steps, while phase 1 runs again for
        // the new function (progressive/pipeline.h): nothing long happens here.
        if (version.field != current_.field) pipeline_->set_field(version.field);
        pipeline_->set_constraint(version.constraint);
        version_frame_due_ = true;
        first_mesh_ms_ = 0;
    }
    current_ = std::move(version);
    converged_ = false;
    converged_message_.reset();
    counters_at_version_ = pipeline_->counters();
    phase1_time_ = {};
    last_progress_ = Clock::now();
    splits_since_progress_ = 0;
    return Start::started;
}

MeshSession::Start MeshSession::restart(FunctionVersion& version, Inbox& inbox) {
    PipelineSettings settings;
    settings.phase1.box = version.box;
    settings.phase1.min_depth = services_.settings.phase1_min_depth;
    settings.phase1.threads = 1;  // sessions run in parallel on the pool; the output is the same
    settings.refine.error_measure = version.error_measure;
    settings.refine.constraint = version.constraint;
    auto pipeline = std::make_unique<Pipeline>(version.field, std::move(settings));
    const auto budget_us =
        std::chrono::duration_cast<std::chrono::microseconds>(services_.settings.first_mesh_budget)
            .count();
    PipelineStep first;
    {
        // The step stops at its budget; the watchdog only catches a runaway evaluation.
        auto guard = services_.watchdog.arm(Clock::now() + services_.settings.eval_timeout, cancel_,
                                            timed_out_);
        first = pipeline->step(WorkBudget(budget_us, WorkBudget::thread_cpu_clock(), &cancel_));
    }
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
    replace_mesh(inbox, version.state.version, first.converged);
    const Clock::time_point now = Clock::now();
    first_mesh_ms_ = milliseconds_between(version.requested, now);
    services_.metrics.first_mesh_seconds.observe(seconds_between(version.requested, now));
    services_.logger.debug("first_mesh", {{"session", id_.to_hex()},
                                          {"version", version.state.version},
                                          {"triangles", wire_.triangle_count()},
                                          {"latency_ms", first_mesh_ms_},
                                          {"resolving", pipeline_->status().resolving}});
    return Start::started;
}

void MeshSession::replace_mesh(Inbox& inbox, std::uint32_t version, bool converged) {
    const RefinedMesh mesh = pipeline_->mesh();
    wire_.reset(mesh.mesh, mesh.triangle_ids, mesh.vertex_ids);
    pending_.take();
    pending_changes_ = 0;
    ++sequence_;
    const Clock::time_point now = Clock::now();
    auto frame = encode_keyframe(converged ? protocol::frame_flags::converged : 0, version);
    for (const auto& client : inbox.subscribers) client->queue().push_keyframe(id_, frame, now);
    inbox.keyframes.clear();  // every subscriber just got this one
    last_flush_ = now;
}

void MeshSession::limit_phase1(Clock::duration spent) {
    if (!pipeline_->status().resolving) return;
    phase1_time_ += spent;
    if (phase1_time_ < services_.settings.eval_timeout) return;
    // Slow to resolve, not broken: the mesh shown so far stays, its unresolved cells reported.
    pipeline_->settle();
    services_.logger.info("phase1_limited",
                          {{"version", current_.state.version},
                           {"unresolved_cells", pipeline_->status().unresolved_cells}});
}

bool MeshSession::refine_turn(Inbox& inbox) {
    const auto slice_us =
        std::chrono::duration_cast<std::chrono::microseconds>(services_.settings.slice).count();
    const WorkBudget budget(slice_us, WorkBudget::thread_cpu_clock(), &cancel_);
    PipelineStep step;
    {
        // The step stops at its budget; the watchdog only catches a runaway evaluation.
        auto guard = services_.watchdog.arm(Clock::now() + services_.settings.eval_timeout, cancel_,
                                            timed_out_);
        step = pipeline_->step(budget);
    }
    if (timed_out_) {
        fail(ErrorCode::eval_timeout, timeout_message(services_.settings.eval_timeout),
             current_.request_id);
        return false;
    }
    limit_phase1(std::chrono::microseconds(budget.elapsed()));
    services_.metrics.splits.add(step.splits);
    services_.metrics.merges.add(step.merges);
    splits_since_progress_ += step.splits;
    // The step's changes are the mesh's, cancelled or not: the next frames build on them.
    if (step.restarted) {
        // Phase 1 resolved more of the topology: the whole mesh is replaced.
        replace_mesh(inbox, current_.state.version, step.converged && !step.cancelled);
    } else {
        gather(pending_, step.delta);
        const MeshDelta& d = step.delta;
        pending_changes_ += d.added_triangles.size() + d.removed_triangles.size() +
                            d.added_vertices.size() + d.moved_vertices.size() +
                            d.removed_vertices.size();
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

void MeshSession::serve_keyframes(const std::vector<KeyframeRequest>& requests) {
    std::shared_ptr<const Bytes> frames[2];  // without and with the catch_up flag
    const std::uint16_t converged = converged_ ? protocol::frame_flags::converged : 0;
    for (const KeyframeRequest& request : requests) {
        auto client = request.client.lock();
        if (!client) continue;
        auto& frame = frames[request.catch_up ? 1 : 0];
        if (!frame) {
            const std::uint16_t flags =
                converged | (request.catch_up ? protocol::frame_flags::catch_up : 0);
            frame = encode_keyframe(flags, current_.state.version);
        }
        if (client->queue().push_keyframe(id_, frame) && converged_message_)
            client->send(*converged_message_);
    }
}

void MeshSession::flush(const Inbox& inbox, bool converged) {
    last_flush_ = Clock::now();
    if (pending_changes_ == 0) return;
    pending_changes_ = 0;
    const WireDelta content = wire_.apply(pending_.take());
    if (content.empty()) return;
    ++sequence_;
    protocol::FrameInfo info;
    info.kind = protocol::FrameKind::delta;
    info.flags = converged ? protocol::frame_flags::converged : 0;
    info.session = id_;
    info.sequence = sequence_;
    info.timestamp_us = unix_time_us();
    info.function_version = current_.state.version;
    protocol::DeltaContent frame_content;
    frame_content.removed = content.removed;
    frame_content.vertices = content.vertices;
    frame_content.triangles = content.triangles;
    frame_content.base_triangle_id = wire_.next_wire_id();
    auto encoded = protocol::encode_delta(info, frame_content, encoding_);
    services_.metrics.encode_seconds.observe(seconds_between(last_flush_, Clock::now()));
    if (!encoded) throw std::runtime_error("delta encoding failed: " + encoded.error().message);
    wire_.commit_wire_ids(content.refiner_ids, encoded.value().triangle_ids);
    auto frame = std::make_shared<const Bytes>(std::move(encoded.value().bytes));
    for (const auto& client : inbox.subscribers) {
        if (client->queue().push_delta(id_, frame, last_flush_) ==
            OutputQueue::DeltaOutcome::dropped_resync)
            request_keyframe(client, true);
    }
}

std::shared_ptr<const Bytes> MeshSession::encode_keyframe(std::uint16_t flags,
                                                          std::uint32_t version) const {
    const KeyframeContent content = wire_.keyframe();
    protocol::FrameInfo info;
    info.kind = protocol::FrameKind::keyframe;
    info.flags = flags;
    info.session = id_;
    info.sequence = sequence_;
    info.timestamp_us = unix_time_us();
    info.function_version = version;
    const Clock::time_point start = Clock::now();
    auto encoded = protocol::encode_keyframe(info, content.vertices, content.triangles,
                                             content.wire_ids, encoding_);
    services_.metrics.encode_seconds.observe(seconds_between(start, Clock::now()));
    if (!encoded) throw std::runtime_error("keyframe encoding failed: " + encoded.error().message);
    return std::make_shared<const Bytes>(std::move(encoded.value().bytes));
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
    if (now - last_progress_ < services_.settings.progress_interval) return;
    auto progress = statistics<protocol::Progress>();
    progress.splits_per_second = splits_since_progress_ / seconds_between(last_progress_, now);
    progress.resolving = pipeline_->status().resolving;
    broadcast(inbox.subscribers, progress, true);
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
    broadcast(inbox.subscribers, message);
    converged_message_ = message;
    services_.logger.debug("converged", {{"session", id_.to_hex()},
                                         {"version", message.version},
                                         {"triangles", message.triangles},
                                         {"total_ms", message.total_ms}});
}

void MeshSession::broadcast(const std::vector<std::shared_ptr<Client>>& to,
                            const protocol::ServerMessage& message, bool droppable) {
    if (to.empty()) return;
    auto text = std::make_shared<const std::string>(protocol::serialize(message));
    for (const auto& client : to) client->queue().push_text(text, droppable);
}

void MeshSession::fail(ErrorCode code, const std::string& message,
                       const std::optional<protocol::RequestId>& request_id) {
    services_.logger.warn(
        "session_failed",
        {{"session", id_.to_hex()}, {"code", protocol::to_string(code)}, {"message", message}});
    services_.metrics.errors[static_cast<int>(code)].add();
    protocol::ErrorReply error;
    error.id = request_id;
    error.session = id_;
    error.code = code;
    error.message = message;
    broadcast(live_subscribers(), error);
    finish(protocol::Closed::Reason::error);
    if (on_end_) on_end_(id_);
}

void MeshSession::finish(protocol::Closed::Reason reason) {
    std::vector<std::shared_ptr<Client>> subscribers = live_subscribers();
    {
        std::lock_guard lock(mutex_);
        finished_ = true;
        services_.metrics.subscriptions.add(-static_cast<std::int64_t>(subscribers_.size()));
        subscribers_.clear();
        keyframe_requests_.clear();
        pending_version_.reset();
    }
    for (const auto& client : subscribers) {
        client->remove_subscription(id_);
        client->queue().forget(id_, false);  // frames already queued still go out
        client->send(protocol::Closed{id_, reason});
    }
    pipeline_.reset();
    wire_ = WireMesh();
}

std::vector<std::shared_ptr<Client>> MeshSession::live_subscribers() {
    std::lock_guard lock(mutex_);
    std::vector<std::shared_ptr<Client>> out;
    for (const auto& weak : subscribers_) {
        if (auto client = weak.lock()) out.push_back(std::move(client));
    }
    return out;
}

}  // namespace isomesh::server
