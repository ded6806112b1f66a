#include "server/output_queue.h"

#include <gtest/gtest.h>

namespace isomesh::server {
namespace {

protocol::SessionId session(std::uint8_t n) {
    protocol::SessionId id;
    id.bytes[0] = n;
    return id;
}

std::shared_ptr<const Bytes> frame(std::size_t size, std::uint8_t tag = 0) {
    return std::make_shared<const Bytes>(size, tag);
}

std::shared_ptr<const std::string> text(std::string s) {
    return std::make_shared<const std::string>(std::move(s));
}

/// Writes everything queued, as the network writer does; returns the stalled sessions reported.
std::vector<protocol::SessionId> drain(OutputQueue& queue,
                                       std::vector<Outgoing>* written = nullptr) {
    std::vector<protocol::SessionId> stalled;
    while (auto message = queue.next()) {
        if (written) written->push_back(*message);
        for (auto& s : queue.written()) stalled.push_back(s);
    }
    return stalled;
}

TEST(OutputQueue, wakes_the_idle_writer_once) {
    int wakeups = 0;
    OutputQueue queue(
        1000, [&] { ++wakeups; }, nullptr);
    queue.push_text(text("a"));
    queue.push_text(text("b"));
    EXPECT_EQ(wakeups, 1);  // the writer is busy until next() finds nothing
    drain(queue);
    queue.push_text(text("c"));
    EXPECT_EQ(wakeups, 2);
}

TEST(OutputQueue, deltas_wait_for_the_keyframe_of_a_new_subscription) {
    OutputQueue queue(1000, {}, nullptr);
    const auto s = session(1);
    EXPECT_EQ(queue.push_delta(s, frame(10)), OutputQueue::DeltaOutcome::dropped_unknown);
    queue.expect_keyframe(s);
    EXPECT_EQ(queue.push_delta(s, frame(10)), OutputQueue::DeltaOutcome::dropped_awaiting);
    EXPECT_TRUE(queue.push_keyframe(s, frame(50)));
    EXPECT_EQ(queue.push_delta(s, frame(10)), OutputQueue::DeltaOutcome::queued);
    std::vector<Outgoing> written;
    drain(queue, &written);
    ASSERT_EQ(written.size(), 2u);
    EXPECT_EQ(written[0].kind, Outgoing::Kind::keyframe);
    EXPECT_EQ(written[1].kind, Outgoing::Kind::delta);
}

TEST(OutputQueue, over_budget_drops_the_sessions_deltas_until_a_catch_up_keyframe) {
    Metrics metrics;
    OutputQueue queue(1000, {}, &metrics);
    const auto slow = session(1), other = session(2);
    for (auto s : {slow, other}) queue.expect_keyframe(s);
    ASSERT_TRUE(queue.push_keyframe(other, frame(400)));
    ASSERT_TRUE(queue.push_keyframe(slow, frame(100)));
    int queued = 0;
    for (int i = 0; i < 20; ++i)
        queued += queue.push_delta(slow, frame(100)) == OutputQueue::DeltaOutcome::queued;
    EXPECT_EQ(queued, 5);  // 400 + 100 + 5 * 100 = 1000 bytes, the budget
    // The sixth delta overflowed: the session's queued deltas went with it, its keyframe and the
    // other session's stay.
    EXPECT_EQ(queue.stream_state(slow), OutputQueue::StreamState::stalled);
    EXPECT_EQ(queue.queued_bytes(), 500u);
    EXPECT_EQ(queue.push_delta(slow, frame(100)), OutputQueue::DeltaOutcome::dropped_stalled);
    EXPECT_GE(metrics.deltas_dropped.value(), 15u);

    // Draining below a quarter of the budget asks for the keyframe, once.
    const auto stalled = drain(queue);
    ASSERT_EQ(stalled.size(), 1u);
    EXPECT_EQ(stalled[0], slow);
    EXPECT_EQ(queue.stream_state(slow), OutputQueue::StreamState::awaiting);
    EXPECT_EQ(queue.push_delta(slow, frame(100)), OutputQueue::DeltaOutcome::dropped_awaiting);
    ASSERT_TRUE(queue.push_keyframe(slow, frame(300)));
    EXPECT_EQ(queue.push_delta(slow, frame(100)), OutputQueue::DeltaOutcome::queued);
    EXPECT_TRUE(drain(queue).empty());
}

TEST(OutputQueue, overflow_with_nothing_left_to_write_asks_for_the_keyframe_at_once) {
    OutputQueue queue(1000, {}, nullptr);
    const auto s = session(1);
    queue.expect_keyframe(s);
    ASSERT_TRUE(queue.push_keyframe(s, frame(100)));
    drain(queue);
    ASSERT_EQ(queue.push_delta(s, frame(600)), OutputQueue::DeltaOutcome::queued);
    // The writer has taken the first delta but not yet asked for more; the second delta
    // overflows and leaves nothing queued: no later write would report the stall.
    auto in_flight = queue.next();
    queue.written();
    ASSERT_EQ(queue.push_delta(s, frame(600)), OutputQueue::DeltaOutcome::queued);
    EXPECT_EQ(queue.push_delta(s, frame(600)), OutputQueue::DeltaOutcome::dropped_resync);
    EXPECT_EQ(queue.stream_state(s), OutputQueue::StreamState::awaiting);
    EXPECT_EQ(queue.queued_bytes(), 0u);
}

TEST(OutputQueue, an_empty_queue_takes_one_frame_of_any_size) {
    OutputQueue queue(100, {}, nullptr);
    const auto s = session(1);
    queue.expect_keyframe(s);
    ASSERT_TRUE(queue.push_keyframe(s, frame(10)));
    drain(queue);
    EXPECT_EQ(queue.push_delta(s, frame(5000)), OutputQueue::DeltaOutcome::queued);
}

TEST(OutputQueue, keyframe_replaces_queued_frames_of_its_session_only) {
    OutputQueue queue(10000, {}, nullptr);
    const auto a = session(1), b = session(2);
    for (auto s : {a, b}) {
        queue.expect_keyframe(s);
        queue.push_keyframe(s, frame(10, 1));
        queue.push_delta(s, frame(10, 2));
    }
    queue.push_text(text("reply"));
    queue.expect_keyframe(a);  // resync: a's queued frames go
    ASSERT_TRUE(queue.push_keyframe(a, frame(10, 3)));
    std::vector<Outgoing> written;
    drain(queue, &written);
    ASSERT_EQ(written.size(), 4u);
    EXPECT_EQ(written[0].session, b);
    EXPECT_EQ(written[1].session, b);
    EXPECT_EQ(*written[2].text, "reply");
    EXPECT_EQ((*written[3].frame)[0], 3);
}

TEST(OutputQueue, forget_drops_or_keeps_queued_frames) {
    OutputQueue queue(10000, {}, nullptr);
    const auto a = session(1);
    queue.expect_keyframe(a);
    queue.push_keyframe(a, frame(10));
    queue.forget(a, false);  // the session ended: what is queued still goes out
    EXPECT_EQ(queue.queued_messages(), 1u);
    EXPECT_FALSE(queue.push_keyframe(a, frame(10)));
    queue.expect_keyframe(a);
    queue.push_keyframe(a, frame(10));
    queue.forget(a);  // unsubscribed: nothing more of it, queued frames included
    EXPECT_EQ(queue.queued_messages(), 0u);
}

TEST(OutputQueue, progress_is_dropped_over_budget_replies_mark_overflow) {
    OutputQueue queue(100, {}, nullptr);
    queue.push_text(text(std::string(90, 'x')));
    queue.push_text(text(std::string(20, 'p')), true);
    EXPECT_EQ(queue.queued_messages(), 1u);
    EXPECT_FALSE(queue.overflowed());
    queue.push_text(text(std::string(200, 'r')));
    EXPECT_TRUE(queue.overflowed());
}

TEST(OutputQueue, large_frames_ahead_of_a_reply_are_no_overflow) {
    OutputQueue queue(100, {}, nullptr);
    const auto s = session(1);
    queue.expect_keyframe(s);
    queue.push_keyframe(s, frame(10000));
    queue.push_text(text("updated"));
    EXPECT_FALSE(queue.overflowed());
}

TEST(OutputQueue, close_refuses_everything_and_settles_the_metrics) {
    Metrics metrics;
    {
        OutputQueue queue(1000, {}, &metrics);
        queue.push_text(text("abc"));
        auto in_flight = queue.next();
        queue.push_text(text("defg"));
        EXPECT_EQ(metrics.queued_bytes.value(), 7);
        queue.close();
        queue.push_text(text("late"));
        EXPECT_EQ(queue.queued_bytes(), 3u);  // only the message in flight
        queue.written();
        EXPECT_EQ(queue.queued_bytes(), 0u);
    }
    EXPECT_EQ(metrics.queued_bytes.value(), 0);
}

}  // namespace
}  // namespace isomesh::server

namespace isomesh::server {
namespace {

/// A frame of `session` whose header carries `sequence` (the rest is not read by the queue).
std::shared_ptr<const Bytes> numbered_frame(std::uint64_t sequence, std::size_t size = 100) {
    Bytes bytes(size, 0);
    for (int i = 0; i < 8; ++i) bytes[24 + i] = static_cast<std::uint8_t>(sequence >> (8 * i));
    return std::make_shared<const Bytes>(std::move(bytes));
}

TEST(OutputQueue, session_messages_never_name_a_frame_the_connection_has_not_reached) {
    OutputQueue queue(1000, {}, nullptr);
    const protocol::SessionId s{{7}};
    const auto message = std::make_shared<const std::string>("converged");
    EXPECT_FALSE(queue.push_session_text(s, message, std::nullopt));  // not followed
    queue.expect_keyframe(s);
    EXPECT_FALSE(queue.push_session_text(s, message, 0));  // awaiting its keyframe
    EXPECT_TRUE(queue.push_session_text(s, message, std::nullopt));
    ASSERT_TRUE(queue.push_keyframe(s, numbered_frame(4)));
    EXPECT_TRUE(queue.push_session_text(s, message, 4));
    EXPECT_FALSE(queue.push_session_text(s, message, 5));
    EXPECT_EQ(queue.push_delta(s, numbered_frame(5)), OutputQueue::DeltaOutcome::queued);
    EXPECT_TRUE(queue.push_session_text(s, message, 5));
    // Over budget the stream stalls: messages wait for the catch-up keyframe.
    EXPECT_EQ(queue.push_delta(s, numbered_frame(6, 2000)),
              OutputQueue::DeltaOutcome::dropped_stalled);
    EXPECT_FALSE(queue.push_session_text(s, message, 6));
    EXPECT_FALSE(queue.push_session_text(s, message, 5));
    queue.forget(s, false);
    EXPECT_FALSE(queue.push_session_text(s, message, std::nullopt));  // after `closed`
}

TEST(OutputQueue, messages_naming_a_dropped_frame_go_with_it) {
    OutputQueue queue(1000, {}, nullptr);
    const protocol::SessionId s{{7}};
    const auto named = [](std::uint64_t sequence) {
        return std::make_shared<const std::string>("progress " + std::to_string(sequence));
    };
    queue.expect_keyframe(s);
    ASSERT_TRUE(queue.push_keyframe(s, numbered_frame(0)));
    drain(queue);  // keyframe 0 reached the connection
    ASSERT_TRUE(queue.push_session_text(s, named(0), 0));
    ASSERT_EQ(queue.push_delta(s, numbered_frame(1)), OutputQueue::DeltaOutcome::queued);
    ASSERT_TRUE(queue.push_session_text(s, named(1), 1));
    // A keyframe replacing the queued delta 1 (phase 1 replaced the mesh) takes its message along.
    ASSERT_TRUE(queue.push_keyframe(s, numbered_frame(2)));
    ASSERT_TRUE(queue.push_session_text(s, named(2), 2));
    ASSERT_EQ(queue.push_delta(s, numbered_frame(3)), OutputQueue::DeltaOutcome::queued);
    ASSERT_TRUE(queue.push_session_text(s, named(3), 3));
    // Over budget: delta 3 is dropped, and the message naming it too.
    ASSERT_EQ(queue.push_delta(s, numbered_frame(4, 2000)),
              OutputQueue::DeltaOutcome::dropped_stalled);
    std::vector<Outgoing> written;
    drain(queue, &written);
    std::vector<std::string> order;
    for (const Outgoing& m : written)
        order.push_back(m.binary() ? "frame " + std::to_string(*m.sequence) : *m.text);
    EXPECT_EQ(order, (std::vector<std::string>{"progress 0", "frame 2", "progress 2"}));
}

TEST(OutputQueue, session_bytes_count_the_frames_queued_for_a_session) {
    OutputQueue queue(100000, {}, nullptr);
    const protocol::SessionId a{{1}}, b{{2}};
    queue.expect_keyframe(a);
    queue.expect_keyframe(b);
    ASSERT_TRUE(queue.push_keyframe(a, numbered_frame(0, 500)));
    ASSERT_TRUE(queue.push_keyframe(b, numbered_frame(0, 300)));
    EXPECT_EQ(queue.push_delta(a, numbered_frame(1, 200)), OutputQueue::DeltaOutcome::queued);
    EXPECT_EQ(queue.session_bytes(a), 700u);
    EXPECT_EQ(queue.session_bytes(b), 300u);
    ASSERT_TRUE(queue.next());  // a's keyframe leaves the queue
    queue.written();
    EXPECT_EQ(queue.session_bytes(a), 200u);
    queue.forget(a);
    EXPECT_EQ(queue.session_bytes(a), 0u);
}

}  // namespace
}  // namespace isomesh::server
