// Budgets and admission (issue 14.2): sessions counted per creating connection, a global cap on
// sessions and on memory, per-session memory and CPU time; the sessions already running keep
// working when new ones are refused.
#include <gtest/gtest.h>

#include <thread>

#include "service_fixture.h"

namespace isomesh::server {
namespace {

using protocol::ErrorCode;
using namespace testing;

const protocol::Subscribe subscribe_to(const protocol::SessionId& session, std::int64_t id) {
    return protocol::Subscribe{id, session};
}

TEST(MeshService, connection_cap_counts_sessions_created_not_subscriptions) {
    ServerConfig config = test_config();
    config.max_sessions_per_connection = 2;
    config.orphan_timeout_s = 0.3;
    Fixture f(config);
    TestConnection a(f.service), b(f.service);
    const auto first = create(a, create_request("x^2+y^2+z^2=4", 500, {}, 1));
    create(a, create_request("x^2+y^2+z^2=3", 500, {}, 2));
    ASSERT_TRUE(request(a, protocol::Unsubscribe{3, first}, 3));  // orphaned: still counts
    a.send(create_request("x^2+y^2+z^2=2", 500, {}, 4));
    ASSERT_TRUE(a.wait_for([&] { return error_for(a, 4); }));
    EXPECT_EQ(error_for(a, 4)->code, ErrorCode::too_many_sessions);
    EXPECT_EQ(f.metrics.sessions_refused[Metrics::kRefusedPerConnection].value(), 1u);

    // Following other connections' sessions is not creating: no limit but the sessions'.
    const auto theirs = create(b, create_request("x^2+y^2+z^2=1", 500, {}, 5));
    const auto more = create(b, create_request("x^2+y^2+z^2=5", 500, {}, 6));
    ASSERT_TRUE(request(a, subscribe_to(theirs, 7), 7));
    ASSERT_TRUE(request(a, subscribe_to(more, 8), 8));
    EXPECT_NE(a.find<protocol::Subscribed>(protocol::RequestId{7}), nullptr);
    EXPECT_NE(a.find<protocol::Subscribed>(protocol::RequestId{8}), nullptr);
    EXPECT_EQ(a.client->created_count(), 2u);

    // Once the orphan expires, its creator may create again.
    ASSERT_TRUE(a.wait_for([&] { return f.service.find(first) == nullptr; }));
    EXPECT_EQ(a.client->created_count(), 1u);
    create(a, create_request("x^2+y^2+z^2=2", 500, {}, 9));
}

TEST(MeshService, subscribe_unsubscribe_cycling_cannot_pile_up_sessions) {
    ServerConfig config = test_config();
    config.max_sessions_per_connection = 2;
    Fixture f(config);
    TestConnection a(f.service);
    int created = 0, refused = 0;
    for (std::int64_t i = 0; i < 8; ++i) {
        a.send(create_request("x^2+y^2+z^2=4", 200, {}, 100 + i));
        ASSERT_TRUE(a.wait_for([&] { return created_reply(a, 100 + i) || error_for(a, 100 + i); }));
        if (const auto* reply = created_reply(a, 100 + i)) {
            ++created;
            ASSERT_TRUE(request(a, protocol::Unsubscribe{200 + i, reply->session}, 200 + i));
        } else {
            EXPECT_EQ(error_for(a, 100 + i)->code, ErrorCode::too_many_sessions);
            ++refused;
        }
    }
    EXPECT_EQ(created, 2);
    EXPECT_EQ(refused, 6);
    EXPECT_EQ(f.service.session_count(), 2u);
}

TEST(MeshService, global_session_cap_refuses_new_sessions_and_the_others_keep_working) {
    ServerConfig config = test_config();
    config.max_sessions = 2;
    Fixture f(config);
    TestConnection a(f.service), b(f.service);
    const auto kept = create(a, create_request("x^2+y^2+z^2=a", 2000, {{"a", 4.0}}, 1));
    const auto other = create(a, create_request("x^2+y^2+z^2=3", 500, {}, 2));
    b.send(create_request("x^2+y^2+z^2=2", 500, {}, 3));
    ASSERT_TRUE(b.wait_for([&] { return error_for(b, 3); }));
    EXPECT_EQ(error_for(b, 3)->code, ErrorCode::server_busy);
    EXPECT_EQ(f.metrics.sessions_refused[Metrics::kRefusedSessions].value(), 1u);

    protocol::Update update;
    update.id = 4;
    update.session = kept;
    update.parameters = protocol::Parameters{{"a", 5.0}};
    a.send(update);
    EXPECT_TRUE(wait_converged(a, kept, 2));

    ASSERT_TRUE(request(a, protocol::Close{5, other}, 5));
    create(b, create_request("x^2+y^2+z^2=2", 500, {}, 6));
}

TEST(MeshService, memory_reservations_refuse_sessions_and_budget_increases_beyond_the_limit) {
    ServerConfig config = test_config();
    config.max_triangles = 1'000'000;
    config.max_memory_mb = 400;  // one 400,000-triangle budget (about 230 MiB) fits, two do not
    Fixture f(config);
    TestConnection a(f.service), b(f.service);
    a.send(create_request("x^2+y^2+z^2=4", 400'000, {}, 1));
    ASSERT_TRUE(a.wait_for([&] { return created_reply(a, 1); }));
    const auto big = created_reply(a, 1)->session;
    ASSERT_TRUE(request(a, protocol::Pause{2, big}, 2));

    b.send(create_request("x^2+y^2+z^2=3", 400'000, {}, 3));
    ASSERT_TRUE(b.wait_for([&] { return error_for(b, 3); }));
    EXPECT_EQ(error_for(b, 3)->code, ErrorCode::server_busy);
    EXPECT_NE(error_for(b, 3)->message.find("fewer triangles"), std::string::npos);

    const auto small = create(b, create_request("x^2+y^2+z^2=3", 2000, {}, 4));
    protocol::Update raise;
    raise.id = 5;
    raise.session = small;
    raise.constraints = protocol::Constraints{400'000, std::nullopt, std::nullopt};
    ASSERT_TRUE(request(b, raise, 5));
    ASSERT_NE(error_for(b, 5), nullptr);
    EXPECT_EQ(error_for(b, 5)->code, ErrorCode::server_busy);
    EXPECT_EQ(f.service.find(small)->latest().state.version, 1u);
    EXPECT_TRUE(wait_converged(b, small));  // the refused update changed nothing
    EXPECT_GE(f.metrics.sessions_refused[Metrics::kRefusedMemory].value(), 2u);
}

TEST(MeshService, session_memory_budget_bounds_the_triangle_budget) {
    ServerConfig config = test_config();
    config.session_memory_mb = 8;
    Fixture f(config);
    TestConnection a(f.service);
    const std::uint64_t affordable =
        ((std::uint64_t{8} << 20) - SessionMemory::kBaseBytes) / SessionMemory::kBytesPerTriangle;
    a.send(create_request("x^2+y^2+z^2=4", affordable + 1, {}, 1));
    ASSERT_TRUE(a.wait_for([&] { return error_for(a, 1); }));
    EXPECT_EQ(error_for(a, 1)->code, ErrorCode::budget_too_large);
    EXPECT_NE(error_for(a, 1)->message.find(std::to_string(affordable)), std::string::npos);
    ASSERT_TRUE(request(a, protocol::Ping{2}, 2));
    const auto* pong = a.find<protocol::Pong>(protocol::RequestId{2});
    ASSERT_TRUE(pong && pong->limits);
    EXPECT_EQ(pong->limits->triangles, affordable);
    EXPECT_EQ(pong->limits->session_memory_bytes, std::uint64_t{8} << 20);
    create(a, create_request("x^2+y^2+z^2=4", affordable, {}, 3));
}

TEST(MeshService, session_over_its_cpu_budget_ends_with_resource_limit_alone) {
    ServerConfig config = test_config();
    config.session_cpu_s = 0.05;
    Fixture f(config);
    TestConnection a(f.service);
    const auto heavy =
        create(a, create_request("x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8=0", 100'000, {}, 1));
    ASSERT_TRUE(a.wait_for([&] { return a.find<protocol::Closed>() != nullptr; }));
    const auto* error = a.find<protocol::ErrorReply>();
    ASSERT_NE(error, nullptr);
    EXPECT_EQ(error->code, ErrorCode::resource_limit);
    EXPECT_EQ(error->session, heavy);
    EXPECT_EQ(a.find<protocol::Closed>()->reason, protocol::Closed::Reason::error);
    EXPECT_EQ(f.service.session_count(), 0u);
    EXPECT_EQ(a.client->created_count(), 0u);
    EXPECT_GE(f.metrics.session_cpu_us.value(), 50'000u);
    // A light session still fits its budget.
    const auto light = create(a, create_request("x^2+y^2+z^2=4", 300, {}, 2));
    EXPECT_TRUE(wait_converged(a, light));
}

}  // namespace
}  // namespace isomesh::server
