// One connection's outgoing messages, with a byte budget (backpressure).
//
// Producers (sessions on worker threads, request handling on network threads) push; the
// connection's writer pops one message at a time, so at most one write is in flight. Every session
// the connection follows has a stream state:
//   live       deltas are queued;
//   stalled    the budget was exceeded: the session's queued deltas were dropped, later ones are
//              dropped too, and once the queue has drained below a quarter of the budget the
//              writer asks the session for a fresh keyframe (state awaiting; when nothing is left
//              to write, push_delta says so and the session sends the keyframe at once);
//   awaiting   a keyframe was asked for (subscription, resync, or stall): deltas are dropped until
//              it comes, which makes the stream live again.
// So a slow reader never makes the server buffer more than the budget plus one keyframe per
// session, and never gets a broken stream: a gap in sequence numbers is always followed by a
// keyframe. A session's own messages (push_session_text) go only to a connection that follows
// it, and one naming a sequence number (`progress`, `converged`) only once this connection's
// stream has reached that frame: a message never names a frame its connection has not received
// first (a lagging connection gets `converged` again after its catch-up keyframe); such a message
// still queued goes with the frame it names when that frame is dropped. Text replies
// are never dropped (their number is bounded by the client's own
// requests), except `progress`, which is informational; a client that lets unsent text messages
// pile up beyond the budget (it sends requests but does not read the replies) is marked
// overflowed and should be disconnected.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "protocol/messages.h"
#include "server/clock.h"
#include "server/metrics.h"

namespace isomesh::server {

using Bytes = std::vector<std::uint8_t>;

struct Outgoing {
    enum class Kind { text, keyframe, delta };
    Kind kind = Kind::text;
    std::shared_ptr<const std::string> text;  ///< for Kind::text
    std::shared_ptr<const Bytes> frame;       ///< for keyframes and deltas
    protocol::SessionId session;              ///< for frames and messages about a session
    /// A frame's sequence number, or the one a message about the session names (`progress`,
    /// `converged`).
    std::optional<std::uint64_t> sequence;
    Clock::time_point created{};

    bool binary() const { return kind != Kind::text; }
    std::size_t size() const { return binary() ? frame->size() : text->size(); }
};

class OutputQueue {
  public:
    enum class StreamState { live, stalled, awaiting };
    enum class DeltaOutcome {
        queued,
        dropped_awaiting,
        dropped_stalled,
        /// Dropped, and nothing is left to write that would report the stall later: the
        /// producer must send this connection a keyframe now (the stream is awaiting it).
        dropped_resync,
        dropped_unknown,
    };

    /// `wakeup` is called (outside the lock) when a message is pushed while the writer is idle:
    /// the writer must then call next() until it returns nothing. `metrics` may be null.
    OutputQueue(std::size_t budget_bytes, std::function<void()> wakeup, Metrics* metrics);
    ~OutputQueue();

    // ---- producers, any thread ----
    /// Starts following a session (state awaiting: its keyframe is on the way). Also the answer to
    /// `resync`: queued frames of the session are dropped.
    void expect_keyframe(const protocol::SessionId& session);
    /// Stops following a session: later frames are refused; its queued frames are dropped
    /// (unsubscribe) or left to be sent (the session ended after them).
    void forget(const protocol::SessionId& session, bool drop_queued = true);
    /// Queues a keyframe for a followed session, replacing its queued frames; the stream is live.
    /// Returns false (and drops it) for a session not followed.
    bool push_keyframe(const protocol::SessionId& session, std::shared_ptr<const Bytes> frame,
                       Clock::time_point created = Clock::now());
    DeltaOutcome push_delta(const protocol::SessionId& session, std::shared_ptr<const Bytes> frame,
                            Clock::time_point created = Clock::now());
    /// Queues a text message; a `droppable` one is dropped when over budget.
    void push_text(std::shared_ptr<const std::string> text, bool droppable = false);
    /// Queues a message about a followed session; dropped when the session is not followed, or
    /// when `sequence` is given and the stream is not live at or past that frame. False when
    /// dropped.
    bool push_session_text(const protocol::SessionId& session,
                           std::shared_ptr<const std::string> text,
                           std::optional<std::uint64_t> sequence, bool droppable = false);
    /// Refuses everything from now on and drops what is queued (the connection is gone).
    void close();

    // ---- the writer, one thread at a time ----
    /// The next message to write (it stays counted until written()), or nothing: the writer is
    /// then idle until the next wakeup.
    std::optional<Outgoing> next();
    /// The message returned by next() has been written. Returns the stalled sessions whose
    /// keyframe the writer must now ask for (their state becomes awaiting).
    std::vector<protocol::SessionId> written();

    // ---- inspection ----
    std::size_t queued_bytes() const;
    std::size_t queued_messages() const;
    std::optional<StreamState> stream_state(const protocol::SessionId& session) const;
    /// Bytes of the session's frames queued and not yet being written.
    std::size_t session_bytes(const protocol::SessionId& session) const;
    bool overflowed() const;
    std::size_t budget() const { return budget_; }

  private:
    using Lock = std::unique_lock<std::mutex>;
    /// Marks the writer busy and returns true when it was idle (the caller then wakes it).
    bool claim_writer(const Lock&);
    void enqueue(const Lock&, Outgoing message);
    /// Removes queued (not in-flight) deltas of `session`, and its keyframes if `keyframes_too`;
    /// counts dropped deltas.
    void drop_frames(const Lock&, const protocol::SessionId& session, bool keyframes_too);
    /// Removes the session's queued messages naming a frame that will not reach the connection
    /// before them (it was dropped), walking the queue in the order it is written.
    void drop_unreached_messages(const Lock&, const protocol::SessionId& session);
    /// Takes `bytes` of the session's frames off its stream's count.
    void uncount(const Lock&, const protocol::SessionId& session, std::size_t bytes);
    void notify(bool wake);

    const std::size_t budget_;
    std::function<void()> wakeup_;
    Metrics* metrics_;
    mutable std::mutex mutex_;
    std::deque<Outgoing> queue_;
    std::size_t queued_bytes_ = 0;  // including the message in flight
    std::size_t in_flight_bytes_ = 0;
    std::size_t text_bytes_ = 0;  // text messages queued, not in flight
    struct Stream {
        StreamState state = StreamState::awaiting;
        std::optional<std::uint64_t> sequence;  // of the last frame queued, while live
        std::size_t queued_bytes = 0;           // frames queued, not in flight
        std::optional<std::uint64_t> written;   // of the last frame handed to the writer
    };
    std::map<protocol::SessionId, Stream> streams_;
    bool writer_busy_ = false;
    bool closed_ = false;
    bool overflowed_ = false;
};

}  // namespace isomesh::server
