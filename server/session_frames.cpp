// MeshSession's frames (session.h): the keyframes and deltas of a session, each encoded once per
// protocol version and queued to every subscriber holding it (a view holder's copy differs only in
// its header's session id). The refiner's changes, gathered over the turns since the last frame,
// go through the version-1 mirror (WireMesh: triangles around moved vertices re-sent) and the
// version-2 mirror (WireMeshV2: only what clients lack); a mirror no subscriber holds follows
// without making frames, and its next subscriber gets a keyframe first.
#include <algorithm>
#include <stdexcept>
#include <utility>

#include "server/session.h"

namespace isomesh::server {
namespace {

/// Adds a refiner step's changes to the batch being gathered for the next delta.
void gather(DeltaBuilder& batch, const MeshDelta& delta) {
    for (std::uint32_t id : delta.removed_triangles) batch.remove_triangle(id);
    for (std::uint32_t id : delta.removed_vertices) batch.remove_vertex(id);
    for (const DeltaVertex& v : delta.added_vertices) batch.add_vertex(v);
    for (const DeltaVertex& v : delta.moved_vertices) batch.move_vertex(v);
    for (const DeltaTriangle& t : delta.added_triangles) batch.add_triangle(t);
}

}  // namespace

void MeshSession::replace_mesh(Inbox& inbox, std::uint32_t version, bool converged,
                               std::array<std::shared_ptr<const Bytes>, 2>* made) {
    const RefinedMesh mesh = pipeline_->mesh();
    wire_.reset(mesh.mesh, mesh.triangle_ids, mesh.vertex_ids);
    take_changes();
    prepare_v2(inbox.subscribers, true);
    ++sequence_;
    const Clock::time_point now = Clock::now();
    const std::uint16_t flags = converged ? protocol::frame_flags::converged : 0;
    std::array<std::shared_ptr<const Bytes>, 2> frames;  // by protocol version, made on first use
    for (const LiveSubscriber& s : inbox.subscribers) {
        const int index = protocol_index(s.client);
        if (!frames[index]) frames[index] = encode_keyframe(flags, version, index + 1);
        push_keyframes({s}, frames[index], now);
    }
    if (made) *made = frames;
    wire_version_ = version;
    last_frame_converged_ = converged;
    // A mesh shown while phase 1 still resolves may be replaced: clients learn it at once, not a
    // progress interval later (a phase 1 done within the interval said nothing of it).
    progress_due_ = pipeline_->status().resolving;
    inbox.keyframes.clear();  // every subscriber just got this one
    last_flush_ = now;
}

void MeshSession::add_changes(MeshDelta delta) {
    pending_changes_ += delta.added_triangles.size() + delta.removed_triangles.size() +
                        delta.added_vertices.size() + delta.moved_vertices.size() +
                        delta.removed_vertices.size();
    if (!pending_step_ && !pending_logged_) {
        pending_step_ = std::move(delta);
        return;
    }
    if (pending_step_) gather(pending_, *std::exchange(pending_step_, std::nullopt));
    gather(pending_, delta);
    pending_logged_ = true;
}

MeshDelta MeshSession::take_changes() {
    pending_changes_ = 0;
    if (pending_step_) return *std::exchange(pending_step_, std::nullopt);
    pending_logged_ = false;
    return pending_.take();
}

const std::shared_ptr<const Bytes>& MeshSession::frame_for(protocol::Access access,
                                                           FrameCopies& frame) const {
    if (access == protocol::Access::control) return frame.control;
    if (!frame.view)
        frame.view =
            std::make_shared<const Bytes>(protocol::with_session(*frame.control, view_id_));
    return frame.view;
}

bool MeshSession::prepare_v2(const std::vector<LiveSubscriber>& subscribers, bool replaced) {
    const bool wanted =
        std::any_of(subscribers.begin(), subscribers.end(),
                    [](const LiveSubscriber& s) { return protocol_index(s.client); });
    if (!wanted) {
        wire_v2_.invalidate();
    } else if (replaced || !wire_v2_.valid()) {
        wire_v2_.reset(wire_.refiner_mesh(), encoding_.grid);
    }
    return wanted;
}

void MeshSession::push_keyframes(const std::vector<LiveSubscriber>& to,
                                 const std::shared_ptr<const Bytes>& frame,
                                 Clock::time_point created) {
    FrameCopies copies{frame, nullptr};
    for (const LiveSubscriber& s : to)
        s.client->queue().push_keyframe(id_for(s.access), frame_for(s.access, copies), created);
}

void MeshSession::serve_keyframes(const std::vector<KeyframeRequest>& requests) {
    FrameCopies frames[2][2];  // by protocol version; without and with the catch_up flag
    const std::uint16_t converged = converged_ && wire_version_ == current_.state.version
                                        ? protocol::frame_flags::converged
                                        : 0;
    for (const KeyframeRequest& request : requests) {
        auto client = request.client.lock();
        if (!client) continue;
        const int index = protocol_index(client);
        auto& frame = frames[index][request.catch_up ? 1 : 0];
        if (!frame.control) {
            const std::uint16_t flags =
                converged | (request.catch_up ? protocol::frame_flags::catch_up : 0);
            if (index == 1 && !wire_v2_.valid())
                wire_v2_.reset(wire_.refiner_mesh(), encoding_.grid);
            // The mirror's content: during a change of function, the version whose frames went
            // out last (the new version's first delta then moves the vertices).
            frame.control = encode_keyframe(flags, wire_version_, index + 1);
        }
        const protocol::SessionId& id = id_for(request.access);
        if (client->queue().push_keyframe(id, frame_for(request.access, frame)) &&
            converged_message_)
            broadcast({{client, request.access}}, *converged_message_,
                      converged_message_->sequence);
    }
}

void MeshSession::flush(const Inbox& inbox, bool converged) {
    last_flush_ = Clock::now();
    // A convergence found after the last frame went out is announced by an empty delta flagged
    // converged, so that the frame a `converged` message names always carries the flag.
    const bool announce = converged && !last_frame_converged_;
    if (pending_changes_ == 0 && !announce) return;
    const MeshDelta delta = take_changes();
    // Without a version-1 subscriber, the version-1 mirror follows the refiner without making a
    // frame: re-sending every triangle around moved vertices in Draco costs tens of milliseconds
    // a slider step, and a version-1 client that subscribes later gets a keyframe first.
    const bool v1_wanted =
        std::any_of(inbox.subscribers.begin(), inbox.subscribers.end(),
                    [](const LiveSubscriber& s) { return protocol_index(s.client) == 0; });
    std::optional<WireDelta> content;
    if (v1_wanted) content = wire_.apply(delta);
    // A delta that changes no triangle for version 1 (which re-sends the triangles around moved
    // vertices) changes nothing a version-2 client sees either.
    const bool changed = content ? !content->empty() : wire_.follow(delta);
    if (!changed && !announce) return;
    ++sequence_;
    last_frame_converged_ = converged;
    protocol::FrameInfo info;
    info.kind = protocol::FrameKind::delta;
    info.flags = converged ? protocol::frame_flags::converged : 0;
    info.session = id_;
    info.sequence = sequence_;
    info.timestamp_us = unix_time_us();
    info.function_version = current_.state.version;
    wire_version_ = current_.state.version;
    flush_v2(inbox, delta, info);
    if (content) flush_v1(inbox, *content, info);
}

void MeshSession::flush_v1(const Inbox& inbox, const WireDelta& content,
                           const protocol::FrameInfo& info) {
    const Clock::time_point start = Clock::now();
    protocol::DeltaContent frame_content;
    frame_content.removed = content.removed;
    frame_content.vertices = content.vertices;
    frame_content.triangles = content.triangles;
    frame_content.base_triangle_id = wire_.next_wire_id();
    auto encoded = protocol::encode_delta(info, frame_content, encoding_);
    services_.metrics.encode_seconds.observe(seconds_between(start, Clock::now()));
    if (!encoded) throw std::runtime_error("delta encoding failed: " + encoded.error().message);
    wire_.commit_wire_ids(content.refiner_ids, encoded.value().triangle_ids);
    FrameCopies frame{std::make_shared<const Bytes>(std::move(encoded.value().bytes)), nullptr};
    for (const LiveSubscriber& s : inbox.subscribers) {
        if (protocol_index(s.client) == 1) continue;
        if (s.client->queue().push_delta(id_for(s.access), frame_for(s.access, frame),
                                         last_flush_) == OutputQueue::DeltaOutcome::dropped_resync)
            request_keyframe(s.client, s.access, true);
    }
}

void MeshSession::flush_v2(const Inbox& inbox, const MeshDelta& delta,
                           const protocol::FrameInfo& v1_info) {
    const bool wanted =
        std::any_of(inbox.subscribers.begin(), inbox.subscribers.end(),
                    [](const LiveSubscriber& s) { return protocol_index(s.client); });
    if (!wanted) wire_v2_.invalidate();
    if (!wanted || !wire_v2_.valid()) return;  // nobody holds the version-2 mesh: keyframes next
    protocol::FrameInfo info = v1_info;
    info.protocol_version = 2;
    const Clock::time_point start = Clock::now();
    auto encoded = wire_v2_.encode(info, delta);
    services_.metrics.encode_seconds.observe(seconds_between(start, Clock::now()));
    if (!encoded) throw std::runtime_error("delta encoding failed: " + encoded.error().message);
    FrameCopies frame{std::make_shared<const Bytes>(std::move(encoded.value().bytes)), nullptr};
    for (const LiveSubscriber& s : inbox.subscribers) {
        if (protocol_index(s.client) != 1) continue;
        if (s.client->queue().push_delta(id_for(s.access), frame_for(s.access, frame),
                                         last_flush_) == OutputQueue::DeltaOutcome::dropped_resync)
            request_keyframe(s.client, s.access, true);
    }
}

std::shared_ptr<const Bytes> MeshSession::encode_keyframe(std::uint16_t flags,
                                                          std::uint32_t version, int protocol) {
    const KeyframeContent content = protocol == 2 ? wire_v2_.keyframe() : wire_.keyframe();
    protocol::FrameInfo info;
    info.protocol_version = static_cast<std::uint8_t>(protocol);
    info.kind = protocol::FrameKind::keyframe;
    info.flags = flags;
    info.session = id_;
    info.sequence = sequence_;
    info.timestamp_us = unix_time_us();
    info.function_version = version;
    const Clock::time_point start = Clock::now();
    const bool renumber = protocol == 2 && wire_v2_.renumberable();
    auto encoded =
        renumber ? protocol::encode_keyframe_numbered(info, content.vertices, content.triangles,
                                                      wire_v2_.next_triangle_id(), encoding_)
                 : protocol::encode_keyframe(info, content.vertices, content.triangles,
                                             content.wire_ids, encoding_);
    services_.metrics.encode_seconds.observe(seconds_between(start, Clock::now()));
    if (!encoded) throw std::runtime_error("keyframe encoding failed: " + encoded.error().message);
    if (renumber) wire_v2_.renumber(content.wire_ids, encoded.value().triangle_ids);
    if (protocol == 2) wire_v2_.sent();
    return std::make_shared<const Bytes>(std::move(encoded.value().bytes));
}

}  // namespace isomesh::server
