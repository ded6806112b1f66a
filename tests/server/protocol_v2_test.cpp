// Protocol version 2 through the service (PROTOCOL.md 4.5, 9): a connection whose first message
// says "v": 2 receives version-2 frames and messages, its replica applies every frame, and it ends
// with the triangles a version-1 client ends with, at bit-equal positions.
#include <gtest/gtest.h>

#include "service_fixture.h"

namespace isomesh::server {
namespace {

using namespace testing;

/// Creates the same session on a version-1 and a version-2 connection, waits for both to
/// converge, and checks that both applied every frame and hold the same mesh.
void expect_same_mesh(const protocol::Create& request) {
    Fixture f;
    TestConnection one(f.service);
    TestConnection two(f.service);
    two.version = 2;
    const auto first = create(one, request);
    const auto second = create(two, request);
    ASSERT_TRUE(wait_converged(one, first));
    ASSERT_TRUE(wait_converged(two, second));
    for (const auto& header : two.frames) EXPECT_EQ(header.protocol_version, 2);
    for (auto outcome : two.outcomes) EXPECT_EQ(outcome, protocol::MeshReplica::Outcome::applied);
    const auto& a = one.replicas.at(first);
    const auto& b = two.replicas.at(second);
    EXPECT_EQ(a.triangle_count(), b.triangle_count());
    EXPECT_EQ(position_triangles(a), position_triangles(b));
    std::size_t deltas = 0;
    for (const auto& header : two.frames) deltas += header.kind == protocol::FrameKind::delta;
    EXPECT_GT(deltas, 0u);
}

TEST(ProtocolV2, sphere_refined_to_its_budget_equals_version_1) {
    expect_same_mesh(create_request("x^2+y^2+z^2=4", 5000, {}, 1));
}

TEST(ProtocolV2, gyroid_refined_to_its_budget_equals_version_1) {
    auto request = create_request("sin(x)cos(y)+sin(y)cos(z)+sin(z)cos(x)=0", 20000, {}, 1);
    request.box = {-6, 6, -6, 6, -6, 6};
    expect_same_mesh(request);
}

TEST(ProtocolV2, a_connection_keeps_the_version_of_its_first_message) {
    Fixture f;
    TestConnection c(f.service);
    c.version = 2;
    c.send(R"({"v":2,"type":"ping","id":1})");
    c.send(R"({"v":1,"type":"ping","id":2})");
    c.send(R"({"v":3,"type":"ping","id":3})");
    ASSERT_TRUE(c.wait_for([&] { return c.messages.size() >= 3; }));
    EXPECT_TRUE(c.find<protocol::Pong>(1));
    const auto* mixed = c.find<protocol::ErrorReply>(2);
    ASSERT_TRUE(mixed);
    EXPECT_EQ(mixed->code, protocol::ErrorCode::unsupported_version);
    const auto* unknown = c.find<protocol::ErrorReply>(3);
    ASSERT_TRUE(unknown);
    EXPECT_EQ(unknown->code, protocol::ErrorCode::unsupported_version);
}

}  // namespace
}  // namespace isomesh::server
