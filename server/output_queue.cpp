#include "server/output_queue.h"

#include <algorithm>

#include "protocol/frame.h"

namespace isomesh::server {

OutputQueue::OutputQueue(std::size_t budget_bytes, std::function<void()> wakeup, Metrics* metrics)
    : budget_(budget_bytes), wakeup_(std::move(wakeup)), metrics_(metrics) {}

OutputQueue::~OutputQueue() {
    if (metrics_) metrics_->queued_bytes.add(-static_cast<std::int64_t>(queued_bytes_));
}

void OutputQueue::expect_keyframe(const protocol::SessionId& session) {
    Lock lock(mutex_);
    if (closed_) return;
    drop_frames(lock, session, true);
    Stream& stream = streams_[session];
    const std::optional<std::uint64_t> written = stream.written;  // those frames were received
    stream = Stream{};
    stream.written = written;
}

void OutputQueue::forget(const protocol::SessionId& session, bool drop_queued) {
    Lock lock(mutex_);
    if (drop_queued) drop_frames(lock, session, true);
    streams_.erase(session);
}

bool OutputQueue::push_keyframe(const protocol::SessionId& session,
                                std::shared_ptr<const Bytes> frame, Clock::time_point created) {
    Lock lock(mutex_);
    auto stream = streams_.find(session);
    if (closed_ || stream == streams_.end()) return false;
    drop_frames(lock, session, true);
    stream->second.state = StreamState::live;
    stream->second.sequence = protocol::frame_sequence(*frame);
    enqueue(lock, {Outgoing::Kind::keyframe, nullptr, std::move(frame), session,
                   stream->second.sequence, created});
    const bool wake = claim_writer(lock);
    lock.unlock();
    if (metrics_) metrics_->keyframes_sent.add();
    notify(wake);
    return true;
}

OutputQueue::DeltaOutcome OutputQueue::push_delta(const protocol::SessionId& session,
                                                  std::shared_ptr<const Bytes> frame,
                                                  Clock::time_point created) {
    Lock lock(mutex_);
    auto stream = streams_.find(session);
    if (closed_ || stream == streams_.end()) return DeltaOutcome::dropped_unknown;
    if (stream->second.state != StreamState::live) {
        if (metrics_) metrics_->deltas_dropped.add();
        return stream->second.state == StreamState::awaiting ? DeltaOutcome::dropped_awaiting
                                                             : DeltaOutcome::dropped_stalled;
    }
    // An empty queue always takes one frame, however large: otherwise no write would ever
    // complete to bring the stream back.
    if (queued_bytes_ > 0 && queued_bytes_ + frame->size() > budget_) {
        // The session's queued deltas go; a queued keyframe stays (it is consistent, and its
        // write will report the stall).
        drop_frames(lock, session, false);
        if (metrics_) metrics_->deltas_dropped.add();
        stream->second.sequence.reset();
        if (queue_.empty() && in_flight_bytes_ == 0) {
            stream->second.state = StreamState::awaiting;
            return DeltaOutcome::dropped_resync;
        }
        stream->second.state = StreamState::stalled;
        return DeltaOutcome::dropped_stalled;
    }
    stream->second.sequence = protocol::frame_sequence(*frame);
    enqueue(lock, {Outgoing::Kind::delta, nullptr, std::move(frame), session,
                   stream->second.sequence, created});
    const bool wake = claim_writer(lock);
    lock.unlock();
    if (metrics_) metrics_->deltas_sent.add();
    notify(wake);
    return DeltaOutcome::queued;
}

void OutputQueue::push_text(std::shared_ptr<const std::string> text, bool droppable) {
    Lock lock(mutex_);
    if (closed_) return;
    if (droppable && queued_bytes_ > 0 && queued_bytes_ + text->size() > budget_) return;
    enqueue(lock, {Outgoing::Kind::text, std::move(text), nullptr, {}, {}, Clock::now()});
    if (text_bytes_ > budget_) overflowed_ = true;
    const bool wake = claim_writer(lock) || overflowed_;
    lock.unlock();
    notify(wake);
}

bool OutputQueue::push_session_text(const protocol::SessionId& session,
                                    std::shared_ptr<const std::string> text,
                                    std::optional<std::uint64_t> sequence, bool droppable) {
    Lock lock(mutex_);
    auto stream = streams_.find(session);
    if (closed_ || stream == streams_.end()) return false;
    if (sequence) {
        const Stream& s = stream->second;
        if (s.state != StreamState::live || !s.sequence || *s.sequence < *sequence) return false;
    }
    if (droppable && queued_bytes_ > 0 && queued_bytes_ + text->size() > budget_) return false;
    enqueue(lock,
            {Outgoing::Kind::text, std::move(text), nullptr, session, sequence, Clock::now()});
    if (text_bytes_ > budget_) overflowed_ = true;
    const bool wake = claim_writer(lock) || overflowed_;
    lock.unlock();
    notify(wake);
    return true;
}

void OutputQueue::close() {
    Lock lock(mutex_);
    closed_ = true;
    const std::size_t dropped = queued_bytes_ - in_flight_bytes_;
    queue_.clear();
    streams_.clear();
    queued_bytes_ = in_flight_bytes_;
    text_bytes_ = 0;
    if (metrics_) metrics_->queued_bytes.add(-static_cast<std::int64_t>(dropped));
}

std::optional<Outgoing> OutputQueue::next() {
    Lock lock(mutex_);
    if (queue_.empty()) {
        writer_busy_ = false;
        return std::nullopt;
    }
    writer_busy_ = true;
    Outgoing message = std::move(queue_.front());
    queue_.pop_front();
    if (!message.binary()) text_bytes_ -= message.size();
    if (message.binary()) {
        uncount(lock, message.session, message.size());
        if (auto stream = streams_.find(message.session); stream != streams_.end())
            stream->second.written = message.sequence;
    }
    in_flight_bytes_ = message.size();
    return message;
}

std::vector<protocol::SessionId> OutputQueue::written() {
    Lock lock(mutex_);
    queued_bytes_ -= in_flight_bytes_;
    if (metrics_) metrics_->queued_bytes.add(-static_cast<std::int64_t>(in_flight_bytes_));
    in_flight_bytes_ = 0;
    std::vector<protocol::SessionId> resume;
    if (queued_bytes_ <= budget_ / 4) {
        for (auto& [session, stream] : streams_) {
            if (stream.state != StreamState::stalled) continue;
            stream.state = StreamState::awaiting;
            resume.push_back(session);
        }
    }
    return resume;
}

std::size_t OutputQueue::queued_bytes() const {
    Lock lock(mutex_);
    return queued_bytes_;
}

std::size_t OutputQueue::queued_messages() const {
    Lock lock(mutex_);
    return queue_.size();
}

std::optional<OutputQueue::StreamState> OutputQueue::stream_state(
    const protocol::SessionId& session) const {
    Lock lock(mutex_);
    auto it = streams_.find(session);
    if (it == streams_.end()) return std::nullopt;
    return it->second.state;
}

std::size_t OutputQueue::session_bytes(const protocol::SessionId& session) const {
    Lock lock(mutex_);
    auto it = streams_.find(session);
    return it == streams_.end() ? 0 : it->second.queued_bytes;
}

bool OutputQueue::overflowed() const {
    Lock lock(mutex_);
    return overflowed_;
}

bool OutputQueue::claim_writer(const Lock&) {
    if (writer_busy_) return false;
    writer_busy_ = true;
    return true;
}

void OutputQueue::enqueue(const Lock&, Outgoing message) {
    queued_bytes_ += message.size();
    if (!message.binary()) text_bytes_ += message.size();
    if (auto stream = streams_.find(message.session); message.binary() && stream != streams_.end())
        stream->second.queued_bytes += message.size();
    if (metrics_) metrics_->queued_bytes.add(static_cast<std::int64_t>(message.size()));
    queue_.push_back(std::move(message));
}

void OutputQueue::drop_frames(const Lock& lock, const protocol::SessionId& session,
                              bool keyframes_too) {
    auto dropped = std::stable_partition(queue_.begin(), queue_.end(), [&](const Outgoing& m) {
        const bool droppable = m.kind == Outgoing::Kind::delta ||
                               (keyframes_too && m.kind == Outgoing::Kind::keyframe);
        return !(droppable && m.session == session);
    });
    std::size_t bytes = 0;
    for (auto it = dropped; it != queue_.end(); ++it) {
        bytes += it->size();
        if (metrics_ && it->kind == Outgoing::Kind::delta) metrics_->deltas_dropped.add();
    }
    const bool any = dropped != queue_.end();
    queue_.erase(dropped, queue_.end());
    uncount(lock, session, bytes);
    queued_bytes_ -= bytes;
    if (metrics_) metrics_->queued_bytes.add(-static_cast<std::int64_t>(bytes));
    if (any) drop_unreached_messages(lock, session);
}

void OutputQueue::drop_unreached_messages(const Lock&, const protocol::SessionId& session) {
    auto stream = streams_.find(session);
    std::optional<std::uint64_t> reached;  // the last frame of the session before this point
    if (stream != streams_.end()) reached = stream->second.written;
    std::deque<Outgoing> kept;
    std::size_t bytes = 0;
    for (Outgoing& m : queue_) {
        if (m.session == session && m.binary()) reached = m.sequence;
        if (m.session == session && !m.binary() && m.sequence &&
            (!reached || *reached < *m.sequence)) {
            bytes += m.size();
            continue;
        }
        kept.push_back(std::move(m));
    }
    queue_ = std::move(kept);
    text_bytes_ -= bytes;
    queued_bytes_ -= bytes;
    if (metrics_) metrics_->queued_bytes.add(-static_cast<std::int64_t>(bytes));
}

void OutputQueue::uncount(const Lock&, const protocol::SessionId& session, std::size_t bytes) {
    auto stream = streams_.find(session);
    if (stream == streams_.end()) return;
    // Frames queued before a forget() and a new subscription were never counted by this stream.
    stream->second.queued_bytes -= std::min(stream->second.queued_bytes, bytes);
}

void OutputQueue::notify(bool wake) {
    if (wake && wakeup_) wakeup_();
}

}  // namespace isomesh::server
