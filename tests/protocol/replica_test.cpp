#include "protocol/replica.h"

#include <gtest/gtest.h>

#include "protocol/tools/sample_mesh.h"

namespace isomesh::protocol {
namespace {

using Outcome = MeshReplica::Outcome;

std::vector<DecodedFrame> decoded_session(const samples::SampleSession& session) {
    std::vector<DecodedFrame> out;
    for (const auto& bytes : session.frames) {
        auto frame = decode_frame(bytes);
        EXPECT_TRUE(frame) << frame.error().message;
        if (frame) out.push_back(std::move(frame.value()));
    }
    return out;
}

class ReplicaTest : public ::testing::Test {
  protected:
    samples::SampleSession session = samples::refining_sphere_session();
    std::vector<DecodedFrame> frames = decoded_session(session);
};

TEST_F(ReplicaTest, applying_every_frame_gives_the_senders_mesh) {
    ASSERT_EQ(frames.size(), 6u);
    MeshReplica replica;
    for (const auto& frame : frames) EXPECT_EQ(replica.apply(frame), Outcome::applied);
    EXPECT_EQ(replica.sorted_triangles(), session.final_triangles);
    EXPECT_EQ(replica.sequence(), 5u);
    EXPECT_EQ(replica.function_version(), 2u);
    EXPECT_TRUE(frames.back().header.flags & frame_flags::converged);
    // Every vertex a triangle uses is known, and none is kept unused.
    std::size_t used = 0;
    std::unordered_map<std::uint32_t, bool> seen;
    for (const auto& [id, vertices] : replica.triangles()) {
        for (std::uint32_t v : vertices) {
            ASSERT_TRUE(replica.vertices().contains(v)) << "vertex " << v;
            if (!seen[v]) ++used, seen[v] = true;
        }
    }
    EXPECT_EQ(used, replica.vertex_count());
}

TEST_F(ReplicaTest, re_added_triangles_move_their_vertices) {
    MeshReplica replica;
    for (std::size_t i = 0; i < 4; ++i) replica.apply(frames[i]);
    const DecodedFrame& move = frames[4];
    ASSERT_EQ(move.header.function_version, 2u);
    ASSERT_FALSE(move.removed.empty());
    int moved = 0;
    for (const Vertex& v : move.vertices) moved += replica.vertices().at(v.id) != v;
    EXPECT_GT(moved, 0);
    EXPECT_EQ(replica.apply(move), Outcome::applied);
    for (const Vertex& v : move.vertices) EXPECT_EQ(replica.vertices().at(v.id), v);
}

TEST_F(ReplicaTest, deltas_before_a_keyframe_wait) {
    MeshReplica replica;
    EXPECT_EQ(replica.apply(frames[1]), Outcome::awaiting_keyframe);
    EXPECT_EQ(replica.triangle_count(), 0u);
}

TEST_F(ReplicaTest, stale_delta_is_skipped) {
    MeshReplica replica;
    replica.apply(frames[0]);
    replica.apply(frames[1]);
    const auto before = replica.sorted_triangles();
    EXPECT_EQ(replica.apply(frames[1]), Outcome::stale);
    EXPECT_EQ(replica.sorted_triangles(), before);
}

TEST_F(ReplicaTest, gap_stops_until_the_next_keyframe) {
    MeshReplica replica;
    replica.apply(frames[0]);
    EXPECT_EQ(replica.apply(frames[2]), Outcome::gap);
    EXPECT_FALSE(replica.synchronized());
    EXPECT_EQ(replica.apply(frames[3]), Outcome::awaiting_keyframe);

    // The server answers `resync` with a keyframe of its current mesh.
    MeshReplica reference;
    for (std::size_t i = 0; i < 3; ++i) reference.apply(frames[i]);
    std::vector<Vertex> vertices;
    for (const auto& [id, v] : reference.vertices()) vertices.push_back(v);
    std::vector<Triangle> triangles;
    std::vector<std::uint64_t> ids;
    for (const auto& t : reference.sorted_triangles()) {
        triangles.push_back({t.vertices});
        ids.push_back(t.id);
    }
    MeshEncoding encoding;
    encoding.grid = QuantizationGrid::for_box({-1.5, 1.5, -1.5, 1.5, -1.5, 1.5});
    FrameInfo info{FrameKind::keyframe, frame_flags::catch_up, frames[0].header.session, 2, 0, 1};
    auto keyframe = encode_keyframe(info, vertices, triangles, ids, encoding);
    ASSERT_TRUE(keyframe);
    auto decoded = decode_frame(keyframe.value().bytes);
    ASSERT_TRUE(decoded);
    EXPECT_EQ(replica.apply(decoded.value()), Outcome::applied);
    for (std::size_t i = 3; i < frames.size(); ++i) {
        EXPECT_EQ(replica.apply(frames[i]), Outcome::applied);
    }
    EXPECT_EQ(replica.sorted_triangles(), session.final_triangles);
}

TEST_F(ReplicaTest, removing_an_unknown_triangle_is_inconsistent) {
    MeshReplica replica;
    replica.apply(frames[0]);
    DecodedFrame forged = frames[1];
    forged.removed.push_back(999'999'999);
    EXPECT_EQ(replica.apply(forged), Outcome::inconsistent);
    EXPECT_FALSE(replica.synchronized());
}

TEST_F(ReplicaTest, adding_a_known_triangle_is_inconsistent) {
    MeshReplica replica;
    replica.apply(frames[0]);
    DecodedFrame forged = frames[1];
    forged.triangles.push_back(frames[0].triangles.front());
    EXPECT_EQ(replica.apply(forged), Outcome::inconsistent);
}

}  // namespace
}  // namespace isomesh::protocol
