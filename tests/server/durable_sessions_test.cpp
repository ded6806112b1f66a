// The service with a session store (server/session_persistence.h), without the network: records
// written before the replies that confirm them, sessions rebuilt from them with identical meshes,
// records deleted on close and expiry, a store that is down, and two services sharing a store.
#include <gtest/gtest.h>

#include <thread>

#include "memory_store.h"
#include "server/mesh_service.h"
#include "test_connection.h"

namespace isomesh::server {
namespace {

using protocol::ErrorCode;
using testing::forward_to;
using testing::MemoryStore;
using testing::TestConnection;

ServerConfig test_config() {
    ServerConfig config;
    config.worker_threads = 2;
    config.log_level = LogLevel::error;
    return config;
}

/// A service on `store` (each service its own metrics).
struct Server {
    Server(MemoryStore& store, ServerConfig c = test_config())
        : config(c), logger(c.log_level), service(config, logger, metrics, forward_to(store)) {}
    ServerConfig config;
    Logger logger;
    Metrics metrics;
    MeshService service;
};

protocol::Create sphere(std::int64_t id, double a = 4, std::uint64_t triangles = 3000) {
    protocol::Create c;
    c.id = id;
    c.source.text = "x^2+y^2+z^2=a";
    c.parameters = {{"a", a}};
    c.box = {-3, 3, -3, 3, -3, 3};
    c.constraints.triangles = triangles;
    return c;
}

const protocol::ErrorReply* error_for(const TestConnection& c, std::int64_t id) {
    return c.find<protocol::ErrorReply>(protocol::RequestId{id});
}

/// Sends `request` and waits for its reply (of any type).
void ask(TestConnection& c, const protocol::ClientMessage& request, std::int64_t id) {
    c.send(request);
    ASSERT_TRUE(c.wait_for([&] {
        for (const auto& m : c.messages) {
            bool answered = false;
            std::visit(
                [&](const auto& message) {
                    if constexpr (requires { message.id; })
                        answered = message.id == protocol::RequestId{id};
                },
                m);
            if (answered) return true;
        }
        return false;
    })) << "no reply to request "
        << id;
}

protocol::SessionId created(TestConnection& c, std::int64_t id) {
    const auto* reply = c.find<protocol::Created>(protocol::RequestId{id});
    EXPECT_NE(reply, nullptr);
    return reply ? reply->session : protocol::SessionId{};
}

bool converged(TestConnection& c, const protocol::SessionId& session, std::uint32_t version) {
    return c.wait_for([&] {
        const auto* m = c.converged(session, version);
        return m && c.replicas[session].synchronized() &&
               c.replicas[session].sequence() >= m->sequence;
    });
}

TEST(DurableSessions, records_are_written_before_created_and_updated_leave) {
    MemoryStore store;
    Server s(store);
    TestConnection a(s.service);
    ask(a, sphere(1), 1);
    const auto id = created(a, 1);
    auto record = store.find(id);
    ASSERT_TRUE(record);
    EXPECT_EQ(record->version, 1u);
    EXPECT_NE(record->definition.find(R"("a":4)"), std::string::npos) << record->definition;

    protocol::Update update;
    update.id = 2;
    update.session = id;
    update.parameters = protocol::Parameters{{"a", 5}};
    ask(a, update, 2);
    ASSERT_NE(a.find<protocol::Updated>(protocol::RequestId{2}), nullptr);
    record = store.find(id);
    EXPECT_EQ(record->version, 2u);
    EXPECT_NE(record->definition.find(R"("a":5)"), std::string::npos) << record->definition;
}

TEST(DurableSessions, a_session_rebuilt_from_its_record_converges_to_the_identical_mesh) {
    MemoryStore store;
    protocol::SessionId id;
    std::vector<std::array<std::uint32_t, 9>> before;
    {
        Server first(store);
        TestConnection a(first.service);
        ask(a, sphere(1, 4, 4000), 1);
        id = created(a, 1);
        ASSERT_TRUE(converged(a, id, 1));
        before = testing::position_triangles(a.replicas[id]);
    }  // gone without a shutdown, as after kill -9: the record stays
    Server second(store);
    EXPECT_EQ(second.metrics.sessions_restored.value(), 1u);
    TestConnection b(second.service);
    ask(b, protocol::Subscribe{1, id}, 1);
    ASSERT_NE(b.find<protocol::Subscribed>(protocol::RequestId{1}), nullptr);
    ASSERT_TRUE(converged(b, id, 1));
    EXPECT_EQ(testing::position_triangles(b.replicas[id]), before);
}

TEST(DurableSessions, close_and_expiry_delete_records) {
    MemoryStore store;
    ServerConfig config = test_config();
    config.orphan_timeout_s = 0.2;
    Server s(store, config);
    TestConnection a(s.service);
    ask(a, sphere(1, 4, 500), 1);
    ask(a, sphere(2, 3, 500), 2);
    const auto closed = created(a, 1);
    const auto orphan = created(a, 2);
    ASSERT_EQ(store.size(), 2u);
    ask(a, protocol::Close{3, closed}, 3);
    EXPECT_FALSE(store.find(closed)) << "deleted before the ack";
    ask(a, protocol::Unsubscribe{4, orphan}, 4);
    ASSERT_TRUE(a.wait_for([&] { return s.metrics.sessions_expired.value() == 1; }));
    EXPECT_EQ(store.size(), 0u);
}

TEST(DurableSessions,
     while_the_store_is_down_new_sessions_and_updates_are_refused_and_live_ones_stream) {
    MemoryStore store;
    Server s(store);
    TestConnection a(s.service);
    ask(a, sphere(1, 4, 2000), 1);
    const auto id = created(a, 1);
    ASSERT_TRUE(converged(a, id, 1));

    store.down = true;
    ask(a, sphere(2), 2);
    ASSERT_NE(error_for(a, 2), nullptr);
    EXPECT_EQ(error_for(a, 2)->code, ErrorCode::store_unavailable);
    protocol::Update update;
    update.id = 3;
    update.session = id;
    update.parameters = protocol::Parameters{{"a", 5}};
    ask(a, update, 3);
    ASSERT_NE(error_for(a, 3), nullptr);
    EXPECT_EQ(error_for(a, 3)->code, ErrorCode::store_unavailable);
    EXPECT_EQ(s.service.find(id)->latest().state.version, 1u) << "a refused update is not applied";
    EXPECT_EQ(s.service.unready(), "session store unreachable");
    EXPECT_EQ(s.metrics.store_up.value(), 0);

    const auto frames = a.frames.size();
    ask(a, protocol::Resync{4, id}, 4);  // the live session still streams
    ASSERT_TRUE(a.wait_for([&] { return a.frames.size() > frames; }));
    ask(a, protocol::Close{5, id}, 5);  // acknowledged; the record goes once the store is back
    ASSERT_NE(a.find<protocol::Ack>(protocol::RequestId{5}), nullptr);
    EXPECT_TRUE(store.find(id));

    store.down = false;
    ASSERT_TRUE(a.wait_for([&] { return !s.service.unready(); }, 5)) << "the probe sees it back";
    ASSERT_TRUE(a.wait_for([&] { return !store.find(id); }, 5)) << "the deletion was retried";
    ask(a, sphere(6), 6);
    EXPECT_NE(a.find<protocol::Created>(protocol::RequestId{6}), nullptr);
    EXPECT_GT(s.metrics.store_errors.value(), 0u);
}

TEST(DurableSessions, a_session_another_server_takes_over_moves_its_subscribers) {
    MemoryStore store(true);  // shared, as Redis is
    Server one(store), two(store);
    TestConnection a(one.service), b(two.service);
    ask(a, sphere(1, 4, 1500), 1);
    const auto id = created(a, 1);
    ASSERT_TRUE(converged(a, id, 1));
    EXPECT_EQ(two.service.session_count(), 0u) << "a shared store loads on demand";

    ask(b, protocol::Subscribe{1, id}, 1);  // the load balancer sent b to the other server
    ASSERT_NE(b.find<protocol::Subscribed>(protocol::RequestId{1}), nullptr);
    EXPECT_EQ(two.service.session_count(), 1u);
    ASSERT_TRUE(a.wait_for([&] { return a.find<protocol::Closed>() != nullptr; }, 5));
    EXPECT_EQ(a.find<protocol::Closed>()->reason, protocol::Closed::Reason::moved);
    EXPECT_EQ(one.service.session_count(), 0u);
    ASSERT_TRUE(converged(b, id, 1));
    EXPECT_EQ(testing::position_triangles(b.replicas[id]),
              testing::position_triangles(a.replicas[id]));
}

TEST(DurableSessions, routes_lead_session_ids_and_a_session_of_another_route_is_refused) {
    MemoryStore store(true);
    Server one(store), two(store);
    const Route route = {0x0a, 0x1b, 0x2c, 0x3d};
    TestConnection a(one.service, route);
    ask(a, sphere(1, 4, 500), 1);
    const auto id = created(a, 1);
    EXPECT_EQ(id.to_hex().substr(0, 8), "0a1b2c3d");
    EXPECT_EQ(route_of(id), route);

    TestConnection elsewhere(two.service, Route{1, 2, 3, 4});
    ask(elsewhere, protocol::Subscribe{1, id}, 1);
    ASSERT_NE(error_for(elsewhere, 1), nullptr);
    EXPECT_EQ(error_for(elsewhere, 1)->code, ErrorCode::wrong_route);
    EXPECT_NE(error_for(elsewhere, 1)->message.find("?route=0a1b2c3d"), std::string::npos);
    protocol::SessionId unknown = id;
    unknown.bytes[15] ^= 1;
    ask(elsewhere, protocol::Subscribe{2, unknown}, 2);
    EXPECT_EQ(error_for(elsewhere, 2)->code, ErrorCode::unknown_session);

    TestConnection same_route(two.service, route);
    ask(same_route, protocol::Subscribe{1, id}, 1);
    EXPECT_NE(same_route.find<protocol::Subscribed>(protocol::RequestId{1}), nullptr);
}

TEST(DurableSessions, shutdown_keeps_records_and_tells_subscribers_the_session_moved) {
    MemoryStore store;
    Server s(store);
    TestConnection a(s.service);
    ask(a, sphere(1, 4, 500), 1);
    const auto id = created(a, 1);
    s.service.shutdown();
    ASSERT_TRUE(a.wait_for([&] { return a.find<protocol::Closed>() != nullptr; }));
    EXPECT_EQ(a.find<protocol::Closed>()->reason, protocol::Closed::Reason::moved);
    EXPECT_TRUE(store.find(id));
}

protocol::SessionId view_of(TestConnection& c, std::int64_t id) {
    const auto* reply = c.find<protocol::Created>(protocol::RequestId{id});
    EXPECT_TRUE(reply && reply->view);
    return reply && reply->view ? *reply->view : protocol::SessionId{};
}

TEST(DurableSessions, a_rebuilt_session_answers_to_its_view_id_read_only) {
    MemoryStore store;
    protocol::SessionId id, view;
    {
        Server first(store);
        TestConnection a(first.service);
        ask(a, sphere(1, 4, 500), 1);
        id = created(a, 1);
        view = view_of(a, 1);
        ASSERT_TRUE(store.find(id));
        EXPECT_EQ(store.find(id)->view, view);
    }  // gone, as after kill -9
    Server second(store);
    TestConnection b(second.service);
    ask(b, protocol::Subscribe{1, view}, 1);
    const auto* subscribed = b.find<protocol::Subscribed>(protocol::RequestId{1});
    ASSERT_NE(subscribed, nullptr);
    EXPECT_EQ(subscribed->session, view);
    EXPECT_EQ(subscribed->access, protocol::Access::view);
    EXPECT_FALSE(subscribed->view) << "a holder of the view id never learns the control id";
    ask(b, protocol::Pause{2, view}, 2);
    ASSERT_NE(error_for(b, 2), nullptr);
    EXPECT_EQ(error_for(b, 2)->code, ErrorCode::read_only);
    ask(b, protocol::Subscribe{3, id}, 3);
    ASSERT_NE(b.find<protocol::Subscribed>(protocol::RequestId{3}), nullptr);
    EXPECT_EQ(b.find<protocol::Subscribed>(protocol::RequestId{3})->view, view);
}

TEST(DurableSessions, another_server_rebuilds_a_session_named_by_its_view_id) {
    MemoryStore store(true);
    Server one(store), two(store);
    const Route route = {0x0a, 0x1b, 0x2c, 0x3d};
    TestConnection a(one.service, route);
    ask(a, sphere(1, 4, 500), 1);
    const auto view = view_of(a, 1);
    EXPECT_EQ(route_of(view), route) << "both ids lead to the session's server";

    TestConnection elsewhere(two.service, Route{1, 2, 3, 4});
    ask(elsewhere, protocol::Subscribe{1, view}, 1);
    ASSERT_NE(error_for(elsewhere, 1), nullptr);
    EXPECT_EQ(error_for(elsewhere, 1)->code, ErrorCode::wrong_route);

    TestConnection b(two.service, route);
    ask(b, protocol::Subscribe{1, view}, 1);
    const auto* subscribed = b.find<protocol::Subscribed>(protocol::RequestId{1});
    ASSERT_NE(subscribed, nullptr);
    EXPECT_EQ(subscribed->access, protocol::Access::view);
    EXPECT_EQ(two.service.session_count(), 1u);
    ASSERT_TRUE(a.wait_for([&] { return a.find<protocol::Closed>() != nullptr; }, 5));
    EXPECT_EQ(a.find<protocol::Closed>()->reason, protocol::Closed::Reason::moved);
}

TEST(RouteOfTarget, reads_the_route_parameter) {
    EXPECT_FALSE(route_of_target("/ws").value());
    EXPECT_FALSE(route_of_target("/ws?other=1").value());
    EXPECT_EQ(route_of_target("/ws?x=1&route=0A1b2c3d").value(), (Route{0x0a, 0x1b, 0x2c, 0x3d}));
    for (const char* bad :
         {"/ws?route=", "/ws?route=0a1b2c3", "/ws?route=0a1b2c3d4", "/ws?route=zz1b2c3d"})
        EXPECT_FALSE(route_of_target(bad).ok()) << bad;
}

}  // namespace
}  // namespace isomesh::server
