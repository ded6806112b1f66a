// New sessions' first meshes kept by request (server/first_mesh_cache.h): the bounds, the key, and
// sessions that send a kept first mesh end with the mesh of their request, also when their own
// first step makes another.
#include "server/first_mesh_cache.h"

#include <gtest/gtest.h>

#include "service_fixture.h"

namespace isomesh::server {
namespace {

using testing::create;
using testing::create_request;
using testing::Fixture;
using testing::test_config;
using testing::TestConnection;
using testing::wait_converged;

std::shared_ptr<const FirstMesh> entry_of(std::uint64_t bytes) {
    auto first = std::make_shared<FirstMesh>();
    first->bytes = bytes;
    return first;
}

FunctionVersion version_of(const protocol::Create& request) {
    VersionResult version = first_version(request, VersionLimits{});
    EXPECT_TRUE(version.ok());
    return version.value();
}

TEST(FirstMeshCache, insert_drops_the_least_recently_used_beyond_its_entries) {
    FirstMeshCache cache(2, 1 << 20);
    cache.insert("a", entry_of(10));
    cache.insert("b", entry_of(10));
    EXPECT_NE(cache.find("a"), nullptr);  // a is now more recent than b
    cache.insert("c", entry_of(10));
    EXPECT_EQ(cache.entries(), 2u);
    EXPECT_NE(cache.find("a"), nullptr);
    EXPECT_EQ(cache.find("b"), nullptr);
    EXPECT_NE(cache.find("c"), nullptr);
    EXPECT_EQ(cache.bytes(), 20u);
}

TEST(FirstMeshCache, insert_keeps_its_bytes_within_the_bound) {
    FirstMeshCache cache(100, 100);
    cache.insert("a", entry_of(60));
    cache.insert("b", entry_of(60));  // a goes
    EXPECT_EQ(cache.find("a"), nullptr);
    EXPECT_EQ(cache.bytes(), 60u);
    cache.insert("huge", entry_of(101));  // never kept
    EXPECT_EQ(cache.find("huge"), nullptr);
    cache.insert("b", entry_of(30));  // replaces b's entry
    EXPECT_EQ(cache.entries(), 1u);
    EXPECT_EQ(cache.bytes(), 30u);
}

TEST(FirstMeshCache, first_mesh_key_is_the_parsed_request) {
    const auto key = [](const char* expression, double a, std::uint64_t triangles = 5000,
                        unsigned protocols = 2) {
        return first_mesh_key(version_of(create_request(expression, triangles, {{"a", a}})),
                              protocols);
    };
    EXPECT_EQ(key("x^2+y^2+z^2=a", 4), key("x^2 + y^2 + z^2 = a", 4));  // spelling aside
    EXPECT_NE(key("x^2+y^2+z^2=a", 4), key("x^2+y^2+z^2=a", 4.000001));
    EXPECT_NE(key("x^2+y^2+z^2=a", 4), key("x^2+y^2+z^2=a+0.5", 3.5));
    EXPECT_NE(key("x^2+y^2+z^2=a", 4), key("x^2+y^2+z^2=a", 4, 6000));
    EXPECT_NE(key("x^2+y^2+z^2=a", 4), key("x^2+y^2+z^2=a", 4, 5000, 1));
    protocol::Create boxed = create_request("x^2+y^2+z^2=a", 5000, {{"a", 4}});
    boxed.box[1] = 3.5;
    EXPECT_NE(key("x^2+y^2+z^2=a", 4), first_mesh_key(version_of(boxed), 2));
}

TEST(FirstMeshCache, seen_before_admits_a_key_the_second_time) {
    FirstMeshCache cache(1, 1 << 20);
    EXPECT_FALSE(cache.seen_before("a"));
    EXPECT_TRUE(cache.seen_before("a"));
    for (const char* key : {"b", "c", "d", "e"}) EXPECT_FALSE(cache.seen_before(key));
    EXPECT_FALSE(cache.seen_before("a"));  // forgotten: at most 4 keys per entry are remembered
}

TEST(FirstMeshCache, sessions_of_one_request_share_the_first_mesh_and_end_alike) {
    Fixture f;
    TestConnection a(f.service), b(f.service);
    const protocol::Create request = create_request("x^2+y^2+z^2+2cos(2x)=5", 5000);
    // Made twice (kept the second time), then shared.
    protocol::Create again = request;
    again.id = 2;
    ASSERT_TRUE(wait_converged(a, create(a, request)));
    const auto first = create(a, again);
    ASSERT_TRUE(wait_converged(a, first));
    const auto second = create(b, request);
    ASSERT_TRUE(wait_converged(b, second));
    EXPECT_EQ(f.metrics.first_mesh_cache_misses.value(), 2u);
    EXPECT_EQ(f.metrics.first_mesh_cache_hits.value(), 1u);
    EXPECT_EQ(f.metrics.first_mesh_cache_mismatches.value(), 0u);
    // The kept keyframe names the second session, and nothing else replaced it.
    EXPECT_EQ(b.frames.front().session, second);
    EXPECT_EQ(b.frames.front().sequence, 0u);
    EXPECT_EQ(b.frames.front().triangle_count, a.frames.front().triangle_count);
    EXPECT_EQ(testing::position_triangles(a.replicas[first]),
              testing::position_triangles(b.replicas[second]));
}

TEST(FirstMeshCache, a_kept_mesh_the_session_does_not_make_is_replaced_by_its_own) {
    // A kept mesh under another request's key: the session's own first step differs, and its
    // mesh follows as a keyframe (what a first step cut by its time budget would give).
    Fixture f;
    TestConnection a(f.service), b(f.service);
    const protocol::Create small = create_request("x^2+y^2+z^2=2", 3000);
    const protocol::Create large = create_request("x^2+y^2+z^2=5", 3000);
    protocol::Create small_again = small;
    small_again.id = 2;
    ASSERT_TRUE(wait_converged(a, create(a, small)));
    ASSERT_TRUE(wait_converged(a, create(a, small_again)));
    std::shared_ptr<const FirstMesh> kept;
    for (unsigned protocols = 1; protocols <= 3 && !kept; ++protocols)
        kept = f.service.first_mesh_cache().find(*first_mesh_key(version_of(small), protocols));
    ASSERT_NE(kept, nullptr);
    for (unsigned protocols = 1; protocols <= 3; ++protocols)
        f.service.first_mesh_cache().insert(*first_mesh_key(version_of(large), protocols), kept);
    const auto keyframes_before = f.metrics.keyframes_sent.value();
    const auto session = create(b, large);
    ASSERT_TRUE(wait_converged(b, session));
    EXPECT_EQ(f.metrics.first_mesh_cache_mismatches.value(), 1u);
    // The kept keyframe, then the session's own. The client may not see the first: a keyframe
    // pushed while an older one still waits in the client's queue replaces it.
    EXPECT_GE(f.metrics.keyframes_sent.value() - keyframes_before, 2u);
    ASSERT_FALSE(b.frames.empty());
    EXPECT_EQ(b.frames[0].kind, protocol::FrameKind::keyframe);

    ServerConfig uncached = test_config();
    uncached.first_mesh_cache = 0;
    Fixture g(uncached);
    TestConnection c(g.service);
    const auto fresh = create(c, large);
    ASSERT_TRUE(wait_converged(c, fresh));
    EXPECT_EQ(g.metrics.first_mesh_cache_hits.value() + g.metrics.first_mesh_cache_misses.value(),
              0u);
    EXPECT_EQ(testing::position_triangles(b.replicas[session]),
              testing::position_triangles(c.replicas[fresh]));
}

}  // namespace
}  // namespace isomesh::server
