// The service without the network: sessions streaming to test connections that decode every frame
// (tests/server/test_connection.h), against meshes computed directly with the core library.
#include "server/mesh_service.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <thread>

#include <glm/geometric.hpp>

#include "progressive/pipeline.h"
#include "service_fixture.h"

namespace isomesh::server {
namespace {

using protocol::ErrorCode;
using testing::create;
using testing::create_request;
using testing::error_for;
using testing::Fixture;
using testing::test_config;
using testing::TestConnection;
using testing::wait_converged;

/// The mesh the CLI would make: the pipeline run to convergence, directly with the core.
RefinedMesh reference_mesh(const protocol::Create& request) {
    VersionResult version = first_version(request, VersionLimits{});
    EXPECT_TRUE(version.ok());
    const FunctionVersion& v = version.value();
    PipelineSettings settings;
    settings.phase1.box = v.box;
    settings.phase1.min_depth = SessionSettings{}.phase1_min_depth;
    settings.refine.error_measure = v.error_measure;
    settings.refine.constraint = v.constraint;
    Pipeline pipeline(v.field, settings);
    pipeline.run_to_convergence();
    return pipeline.mesh();
}

class GallerySurface : public ::testing::TestWithParam<const char*> {};

INSTANTIATE_TEST_SUITE_P(MeshService, GallerySurface,
                         ::testing::Values("sqrt(x^2+y^2+z^2)=2", "x^2+y^2+z^2+2cos(2x)=5",
                                           "(sqrt(x^2+y^2)-1.8)^2+z^2=0.5",
                                           "x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8=0", "10x^2+y^2+z^2=5"));

TEST_P(GallerySurface, streams_a_keyframe_then_deltas_to_the_reference_mesh) {
    Fixture f;
    TestConnection a(f.service);
    const auto request = create_request(GetParam(), 4000);
    const auto session = create(a, request);
    ASSERT_TRUE(wait_converged(a, session));

    ASSERT_FALSE(a.frames.empty());
    EXPECT_EQ(a.frames.front().kind, protocol::FrameKind::keyframe);
    // PROTOCOL.md 6.3: the first keyframe has sequence 0, unless a newer keyframe replaced it
    // (and the frames before it) while still queued: so numbers grow, each delta's one more than
    // the frame before. Keyframes only while phase 1 resolves the topology (each replaces the
    // whole mesh, PROTOCOL.md 3.4), deltas after.
    bool delta_seen = false;
    for (std::size_t i = 1; i < a.frames.size(); ++i) {
        if (a.frames[i].kind == protocol::FrameKind::delta) {
            EXPECT_EQ(a.frames[i].sequence, a.frames[i - 1].sequence + 1) << i;
        } else {
            EXPECT_GT(a.frames[i].sequence, a.frames[i - 1].sequence) << i;
        }
        if (a.frames[i].kind == protocol::FrameKind::delta) delta_seen = true;
        if (delta_seen) {
            EXPECT_EQ(a.frames[i].kind, protocol::FrameKind::delta) << i;
        }
    }
    EXPECT_EQ(a.converged(session, 1)->sequence, a.frames.back().sequence);
    for (auto outcome : a.outcomes) EXPECT_EQ(outcome, protocol::MeshReplica::Outcome::applied);

    // The same mesh as the pipeline's, triangle for triangle, at the positions of the session's
    // 14-bit grid (ids may differ: they depend on how often phase 1 replaced the mesh).
    const auto& replica = a.replicas[session];
    EXPECT_TRUE(testing::watertight(replica));
    const RefinedMesh reference = reference_mesh(request);
    EXPECT_EQ(replica.triangle_count(), reference.mesh.triangle_count());
    EXPECT_EQ(testing::compare_on_grid(replica, reference.mesh,
                                       protocol::QuantizationGrid::for_box(request.box)),
              "");
    EXPECT_EQ(a.converged(session, 1)->triangles, reference.mesh.triangle_count());
}

TEST(MeshService, late_joiner_and_creator_end_identical) {
    Fixture f;
    TestConnection a(f.service), b(f.service);
    const auto session = create(a, create_request("x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8=0", 20000));
    ASSERT_TRUE(a.wait_for([&] { return a.frames.size() >= 2; }));           // refinement under way
    const std::uint64_t sequence_before_joining = a.frames.back().sequence;  // 1 or more
    protocol::Subscribe subscribe;
    subscribe.id = 7;
    subscribe.session = session;
    b.send(subscribe);
    ASSERT_TRUE(wait_converged(a, session));
    ASSERT_TRUE(wait_converged(b, session));
    ASSERT_NE(b.find<protocol::Subscribed>(protocol::RequestId{7}), nullptr);
    EXPECT_EQ(b.frames.front().kind, protocol::FrameKind::keyframe);
    EXPECT_GE(b.frames.front().sequence, sequence_before_joining);  // joined mid-stream
    EXPECT_EQ(testing::canonical_triangles(a.replicas[session]),
              testing::canonical_triangles(b.replicas[session]));
    EXPECT_EQ(a.replicas[session].sequence(), b.replicas[session].sequence());
}

TEST(MeshService, slow_reader_stays_within_budget_then_catches_up_with_a_keyframe) {
    ServerConfig config = test_config();
    config.queue_bytes = 16 * 1024;
    Fixture f(config);
    TestConnection fast(f.service), slow(f.service);
    const auto request = create_request("x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8=0", 60000);
    const auto session = create(fast, request);
    protocol::Subscribe subscribe;
    subscribe.session = session;
    slow.send(subscribe);
    slow.pump();  // the `subscribed` reply
    slow.reading = false;
    std::size_t most_queued = 0;
    ASSERT_TRUE(fast.wait_for([&] {
        most_queued = std::max(most_queued, slow.client->queue().queued_bytes());
        return fast.converged(session, 1) != nullptr;
    }));
    // Deltas beyond the budget were dropped: at most the budget, the keyframe the slow reader
    // had not read yet (it is still queued) and a few replies.
    std::size_t keyframe_bytes = 0;
    while (auto message = slow.client->queue().next()) {
        if (message->kind == Outgoing::Kind::keyframe) keyframe_bytes += message->size();
        slow.client->queue().written();
    }
    EXPECT_GT(keyframe_bytes, 0u);
    EXPECT_LE(most_queued, f.config.queue_bytes + keyframe_bytes + 4096);
    EXPECT_GT(f.metrics.deltas_dropped.value(), 0u);

    ASSERT_TRUE(wait_converged(fast, session));  // the fast reader may have had to catch up too
    slow.reading = true;
    slow.frames.clear();  // what was just drained by hand was not applied: start from a keyframe
    protocol::Resync resync;
    resync.session = session;
    slow.send(resync);
    ASSERT_TRUE(wait_converged(slow, session));
    const bool caught_up = std::any_of(slow.frames.begin(), slow.frames.end(), [](const auto& h) {
        return h.kind == protocol::FrameKind::keyframe &&
               (h.flags & protocol::frame_flags::catch_up);
    });
    EXPECT_TRUE(caught_up);
    for (auto outcome : slow.outcomes)
        EXPECT_NE(outcome, protocol::MeshReplica::Outcome::inconsistent);
    EXPECT_EQ(testing::canonical_triangles(slow.replicas[session]),
              testing::canonical_triangles(fast.replicas[session]));
    EXPECT_TRUE(testing::watertight(slow.replicas[session]));
}

TEST(MeshService, rapid_updates_end_at_the_last_version) {
    Fixture f;
    TestConnection a(f.service);
    const auto session = create(a, create_request("x^2+y^2+z^2=a", 8000, {{"a", 1.0}}));
    for (int i = 1; i <= 20; ++i) {
        protocol::Update update;
        update.id = 100 + i;
        update.session = session;
        update.parameters = protocol::Parameters{{"a", 1.0 + 0.25 * i}};
        a.send(update);
        a.pump();
    }
    ASSERT_TRUE(wait_converged(a, session, 21));
    for (int i = 1; i <= 20; ++i)
        ASSERT_NE(a.find<protocol::Updated>(protocol::RequestId{100 + i}), nullptr);
    const auto& replica = a.replicas[session];
    EXPECT_EQ(replica.function_version(), 21u);
    EXPECT_TRUE(testing::watertight(replica));
    const double radius = std::sqrt(6.0);
    for (const auto& [id, v] : replica.vertices())
        ASSERT_NEAR(std::sqrt(glm::dot(glm::dvec3(v.position), glm::dvec3(v.position))), radius,
                    2e-3);
    EXPECT_EQ(a.converged(session, 21)->triangles, replica.triangle_count());
}

TEST(MeshService, update_after_convergence_moves_every_vertex_onto_the_new_surface) {
    Fixture f;
    TestConnection a(f.service);
    const auto session = create(a, create_request("x^2+y^2+z^2=a", 3000, {{"a", 4.0}}));
    ASSERT_TRUE(wait_converged(a, session));
    const auto sequence = a.replicas[session].sequence();
    protocol::Update update;
    update.session = session;
    update.parameters = protocol::Parameters{{"a", 4.41}};  // radius 2 -> 2.1: same topology
    a.send(update);
    ASSERT_TRUE(wait_converged(a, session, 2));
    const auto& replica = a.replicas[session];
    EXPECT_GT(replica.sequence(), sequence);
    EXPECT_TRUE(testing::watertight(replica));
    for (const auto& [id, v] : replica.vertices())
        ASSERT_NEAR(std::sqrt(glm::dot(glm::dvec3(v.position), glm::dvec3(v.position))), 2.1, 1e-3);
}

TEST(MeshService, every_bad_request_gets_its_error_and_the_connection_stays_usable) {
    ServerConfig config = test_config();
    config.max_message_bytes = 4096;
    Fixture f(config);
    TestConnection a(f.service);
    const auto session = create(a, create_request("x^2+y^2+z^2=4", 1000, {}, 1));

    a.send("{not json");
    a.send(R"({"v":1,"type":"teleport","id":2})");
    a.send(R"({"v":1,"type":"subscribe","id":3,"session":"00000000000000000000000000000000"})");
    a.send(create_request("x^2+y^2+(z=4", 1000, {}, 4));
    a.send(R"({"v":1,"type":"ping","id":5,"pad":")" + std::string(5000, 'x') + "\"}");
    a.send(create_request("x^2+y^2+z^2=4", 200'000, {}, 6));
    a.send(create_request("x^2+y^2+z^2=a", 1000, {}, 7));  // no value for a
    create(a, create_request("x^2+y^2+z^2=1", 100, {}, 8));
    create(a, create_request("x^2+y^2+z^2=2", 100, {}, 9));
    a.send(create_request("x^2+y^2+z^2=3", 100, {}, 10));  // a fourth session
    protocol::Ping ping;
    ping.id = 11;
    a.send(ping);
    ASSERT_TRUE(a.wait_for([&] { return a.find<protocol::Pong>(protocol::RequestId{11}); }));

    const std::pair<std::int64_t, ErrorCode> expected[] = {
        {2, ErrorCode::unknown_type},   {3, ErrorCode::unknown_session},
        {4, ErrorCode::bad_expression}, {6, ErrorCode::budget_too_large},
        {7, ErrorCode::bad_field},      {10, ErrorCode::too_many_sessions},
    };
    for (const auto& [id, code] : expected) {
        const auto* error = error_for(a, id);
        ASSERT_NE(error, nullptr) << id;
        EXPECT_EQ(error->code, code) << id << ": " << error->message;
    }
    EXPECT_EQ(error_for(a, 4)->column, 11u);  // the '=' inside the bracket
    bool saw_bad_json = false, saw_too_large = false;
    for (const auto& m : a.messages) {
        if (const auto* e = std::get_if<protocol::ErrorReply>(&m)) {
            saw_bad_json |= e->code == ErrorCode::bad_json;
            saw_too_large |= e->code == ErrorCode::too_large;
        }
    }
    EXPECT_TRUE(saw_bad_json);
    EXPECT_TRUE(saw_too_large);
    // The first session was never disturbed.
    EXPECT_TRUE(wait_converged(a, session));
    EXPECT_TRUE(testing::watertight(a.replicas[session]));
}

TEST(MeshService, evaluation_over_the_time_limit_ends_only_that_session) {
    ServerConfig config = test_config();
    config.eval_timeout_ms = 1;
    Fixture f(config);
    TestConnection a(f.service);
    // Hundreds of terms: phase 1 of this takes far longer than a millisecond.
    std::string heavy = "0";
    for (int i = 1; i <= 300; ++i) heavy += "+sin(" + std::to_string(i) + "x+y*z)";
    heavy += "=1";
    const auto session = create(a, create_request(heavy, 1000, {}, 1));
    ASSERT_TRUE(a.wait_for([&] { return a.find<protocol::Closed>() != nullptr; }));
    const auto* error = a.find<protocol::ErrorReply>(protocol::RequestId{1});
    ASSERT_NE(error, nullptr);
    EXPECT_EQ(error->code, ErrorCode::eval_timeout);
    EXPECT_EQ(error->session, session);
    EXPECT_EQ(a.find<protocol::Closed>()->reason, protocol::Closed::Reason::error);
    EXPECT_EQ(f.service.session_count(), 0u);
    EXPECT_EQ(a.client->subscription_count(), 0u);
    protocol::Ping ping;
    ping.id = 2;
    a.send(ping);
    EXPECT_TRUE(a.wait_for([&] { return a.find<protocol::Pong>(protocol::RequestId{2}); }));
}

TEST(MeshService, vanished_client_leaves_no_session_behind) {
    ServerConfig config = test_config();
    config.orphan_timeout_s = 0.2;
    Fixture f(config);
    {
        TestConnection a(f.service);
        create(a, create_request("x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8=0", 100'000));
        a.reading = false;
    }  // disconnects mid-stream
    TestConnection observer(f.service);
    EXPECT_TRUE(observer.wait_for([&] {
        return f.service.session_count() == 0 && f.metrics.sessions.value() == 0 &&
               f.metrics.busy_workers.value() == 0 && f.metrics.subscriptions.value() == 0;
    }));
    EXPECT_EQ(f.metrics.sessions_expired.value(), 1u);
}

TEST(MeshService, close_pause_resume_and_resync) {
    Fixture f;
    TestConnection a(f.service), b(f.service);
    const auto session = create(a, create_request("x^2+y^2+z^2=4", 20000));
    auto request = [&](protocol::ClientMessage message) { a.send(message); };
    ASSERT_TRUE(a.wait_for([&] { return !a.frames.empty(); }));  // pause once the mesh is there
    request(protocol::Pause{2, session});
    ASSERT_TRUE(a.wait_for([&] { return a.find<protocol::Ack>(protocol::RequestId{2}); }));
    // The turn under way when the pause came flushes its changes; then nothing more comes.
    ASSERT_TRUE(a.wait_for(
        [&] { return f.metrics.busy_workers.value() == 0 && f.metrics.run_queue.value() == 0; }));
    a.pump();
    const auto frames_when_paused = a.frames.size();
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    a.pump();
    EXPECT_EQ(a.frames.size(), frames_when_paused);
    request(protocol::Resync{3, session});
    ASSERT_TRUE(a.wait_for([&] { return a.frames.size() > frames_when_paused; }));
    EXPECT_TRUE(a.frames.back().flags & protocol::frame_flags::catch_up);
    request(protocol::Resume{4, session});
    ASSERT_TRUE(wait_converged(a, session));

    b.send(protocol::Subscribe{5, session});
    ASSERT_TRUE(wait_converged(b, session));
    b.send(protocol::Close{6, session});
    ASSERT_TRUE(b.wait_for([&] { return b.find<protocol::Closed>() != nullptr; }));
    ASSERT_TRUE(a.wait_for([&] { return a.find<protocol::Closed>() != nullptr; }));
    EXPECT_EQ(a.find<protocol::Closed>()->reason, protocol::Closed::Reason::closed);
    EXPECT_NE(b.find<protocol::Ack>(protocol::RequestId{6}), nullptr);
    b.send(protocol::Subscribe{7, session});
    ASSERT_TRUE(b.wait_for([&] { return error_for(b, 7) != nullptr; }));
    EXPECT_EQ(error_for(b, 7)->code, ErrorCode::unknown_session);
}

TEST(MeshService, shutdown_closes_sessions_and_refuses_new_work) {
    Fixture f;
    TestConnection a(f.service);
    const auto session = create(a, create_request("x^2+y^2+z^2=4", 20000));
    f.service.shutdown();
    ASSERT_TRUE(a.wait_for([&] { return a.find<protocol::Closed>() != nullptr; }));
    EXPECT_EQ(a.find<protocol::Closed>()->reason, protocol::Closed::Reason::shutdown);
    EXPECT_EQ(a.find<protocol::Closed>()->session, session);
    a.send(create_request("x^2+y^2+z^2=4", 100, {}, 9));
    ASSERT_TRUE(a.wait_for([&] { return error_for(a, 9) != nullptr; }));
    EXPECT_EQ(error_for(a, 9)->code, ErrorCode::unavailable);
}

}  // namespace
}  // namespace isomesh::server
