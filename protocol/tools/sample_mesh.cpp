// Synthetic meshes for tests and samples (see sample_mesh.h).
#include "protocol/tools/sample_mesh.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <numeric>
#include <set>

#include <glm/geometric.hpp>

namespace isomesh::protocol::samples {
namespace {

using Edge = std::pair<std::uint32_t, std::uint32_t>;

Edge edge_key(std::uint32_t a, std::uint32_t b) {
    return a < b ? Edge{a, b} : Edge{b, a};
}

/// Midpoint vertices by edge, creating each once, ids counting up from `next_id`.
class Midpoints {
  public:
    Midpoints(const std::vector<Vertex>& base, std::uint32_t base_first_id, std::uint32_t next_id,
              float radius)
        : base_(base), base_first_id_(base_first_id), next_id_(next_id), radius_(radius) {}

    std::uint32_t operator()(std::uint32_t a, std::uint32_t b) {
        auto [it, added] = ids_.emplace(edge_key(a, b), next_id_);
        if (added) {
            const glm::vec3 direction = glm::normalize(position(a) + position(b));
            created_.push_back({next_id_++, direction * radius_, direction});
        }
        return it->second;
    }
    const glm::vec3& position(std::uint32_t id) const {
        if (id >= base_first_id_ && id - base_first_id_ < base_.size()) {
            return base_[id - base_first_id_].position;
        }
        return created_[id - created_first_id()].position;
    }
    std::uint32_t created_first_id() const {
        return next_id_ - static_cast<std::uint32_t>(created_.size());
    }
    std::vector<Vertex>& created() { return created_; }

  private:
    const std::vector<Vertex>& base_;
    std::uint32_t base_first_id_;
    std::uint32_t next_id_;
    float radius_;
    std::map<Edge, std::uint32_t> ids_;
    std::vector<Vertex> created_;
};

void split_in_four(const Triangle& t, Midpoints& midpoint, std::vector<Triangle>& out) {
    const auto [a, b, c] = t.vertices;
    const std::uint32_t ab = midpoint(a, b);
    const std::uint32_t bc = midpoint(b, c);
    const std::uint32_t ca = midpoint(c, a);
    out.push_back({{a, ab, ca}});
    out.push_back({{ab, b, bc}});
    out.push_back({{ca, bc, c}});
    out.push_back({{ab, bc, ca}});
}

glm::vec3 centroid(const SampleMesh& mesh, const Triangle& t, std::uint32_t first_id) {
    glm::vec3 sum(0.0f);
    for (std::uint32_t v : t.vertices) sum += mesh.vertices[v - first_id].position;
    return sum / 3.0f;
}

}  // namespace

SampleMesh icosphere(int subdivisions, float radius, std::uint32_t first_id) {
    const float g = (1.0f + std::sqrt(5.0f)) / 2.0f;
    const std::vector<glm::vec3> corners = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0},
                                            {0, -1, g}, {0, 1, g}, {0, -1, -g}, {0, 1, -g},
                                            {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
    const std::vector<std::array<std::uint32_t, 3>> faces = {
        {0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
        {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
        {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
    SampleMesh mesh;
    for (std::size_t i = 0; i < corners.size(); ++i) {
        const glm::vec3 n = glm::normalize(corners[i]);
        mesh.vertices.push_back({first_id + static_cast<std::uint32_t>(i), n * radius, n});
    }
    for (const auto& f : faces) {
        mesh.triangles.push_back({{f[0] + first_id, f[1] + first_id, f[2] + first_id}});
    }
    for (int level = 0; level < subdivisions; ++level) {
        std::vector<std::size_t> all(mesh.triangles.size());
        std::iota(all.begin(), all.end(), std::size_t{0});
        const auto next_id = first_id + static_cast<std::uint32_t>(mesh.vertices.size());
        Subdivision finer = subdivide(mesh, all, next_id, radius);
        mesh.vertices.insert(mesh.vertices.end(), finer.vertices.begin(), finer.vertices.end());
        mesh.triangles = std::move(finer.triangles);
    }
    return mesh;
}

std::vector<std::size_t> cap(const SampleMesh& mesh, glm::vec3 direction, std::size_t count) {
    const glm::vec3 axis = glm::normalize(direction);
    const std::uint32_t first_id = mesh.vertices.front().id;
    std::vector<std::pair<float, std::size_t>> by_angle;
    by_angle.reserve(mesh.triangles.size());
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
        const glm::vec3 c = glm::normalize(centroid(mesh, mesh.triangles[i], first_id));
        by_angle.emplace_back(-glm::dot(c, axis), i);
    }
    count = std::min(count, by_angle.size());
    std::partial_sort(by_angle.begin(), by_angle.begin() + static_cast<std::ptrdiff_t>(count),
                      by_angle.end());
    std::vector<std::size_t> indices(count);
    for (std::size_t i = 0; i < count; ++i) indices[i] = by_angle[i].second;
    std::sort(indices.begin(), indices.end());
    return indices;
}

std::vector<Triangle> pick(const SampleMesh& mesh, const std::vector<std::size_t>& indices) {
    std::vector<Triangle> out;
    out.reserve(indices.size());
    for (std::size_t i : indices) out.push_back(mesh.triangles[i]);
    return out;
}

Subdivision subdivide(const SampleMesh& mesh, const std::vector<std::size_t>& indices,
                      std::uint32_t first_new_id, float radius) {
    Midpoints midpoint(mesh.vertices, mesh.vertices.front().id, first_new_id, radius);
    Subdivision out;
    out.triangles.reserve(4 * indices.size());
    for (std::size_t i : indices) split_in_four(mesh.triangles[i], midpoint, out.triangles);
    out.vertices = std::move(midpoint.created());
    return out;
}

SessionId sample_session_id() {
    SessionId id;
    for (std::size_t i = 0; i < id.bytes.size(); ++i) {
        id.bytes[i] = static_cast<std::uint8_t>(0x11 * i);
    }
    return id;
}

namespace {

/// The sender's side of a session: the current mesh with each triangle's wire id.
struct SenderMesh {
    SampleMesh mesh;
    std::vector<std::uint64_t> ids;

    /// Replaces the triangles at `chosen` (ascending) by `split`, numbered `split_ids`.
    void apply_split(const std::vector<std::size_t>& chosen, Subdivision split,
                     const std::vector<std::uint64_t>& split_ids) {
        for (auto it = chosen.rbegin(); it != chosen.rend(); ++it) {
            mesh.triangles.erase(mesh.triangles.begin() + static_cast<std::ptrdiff_t>(*it));
            ids.erase(ids.begin() + static_cast<std::ptrdiff_t>(*it));
        }
        mesh.vertices.insert(mesh.vertices.end(), split.vertices.begin(), split.vertices.end());
        mesh.triangles.insert(mesh.triangles.end(), split.triangles.begin(), split.triangles.end());
        ids.insert(ids.end(), split_ids.begin(), split_ids.end());
    }

    std::vector<FrameTriangle> sorted() const {
        std::vector<FrameTriangle> out;
        for (std::size_t i = 0; i < ids.size(); ++i)
            out.push_back({ids[i], canonical_rotation(mesh.triangles[i].vertices)});
        std::sort(out.begin(), out.end(),
                  [](const FrameTriangle& a, const FrameTriangle& b) { return a.id < b.id; });
        return out;
    }
};

/// Sample inputs are valid by construction: a failure here is a bug in the library.
template <class T>
T expect_ok(Result<T> result) {
    if (!result.ok()) {
        std::fprintf(stderr, "sample session: %s\n", result.error().message.c_str());
        std::abort();
    }
    return std::move(result).value();
}

}  // namespace

SampleSession refining_sphere_session() {
    MeshEncoding encoding;
    encoding.grid = QuantizationGrid::for_box({-1.5, 1.5, -1.5, 1.5, -1.5, 1.5});
    FrameInfo info{FrameKind::keyframe, 0, sample_session_id(), 0, 1'700'000'000'000'000, 1};
    SenderMesh sender{icosphere(2), {}};
    for (std::size_t i = 0; i < sender.mesh.triangles.size(); ++i)
        sender.ids.push_back(1000 + 7 * i);

    SampleSession session;
    session.frames.push_back(expect_ok(encode_keyframe(info, sender.mesh.vertices,
                                                       sender.mesh.triangles, sender.ids, encoding))
                                 .bytes);
    info.kind = FrameKind::delta;
    std::uint64_t next_triangle_id = 100000;
    for (const glm::vec3 direction :
         {glm::vec3(0, 0, 1), glm::vec3(1, 0.2f, 0), glm::vec3(-0.3f, -1, 0.1f)}) {
        const auto chosen = cap(sender.mesh, direction, 25);
        auto split =
            subdivide(sender.mesh, chosen, static_cast<std::uint32_t>(sender.mesh.vertices.size()));
        std::vector<std::uint64_t> removed;
        for (std::size_t i : chosen) removed.push_back(sender.ids[i]);
        std::vector<Vertex> all = sender.mesh.vertices;
        all.insert(all.end(), split.vertices.begin(), split.vertices.end());
        ++info.sequence;
        info.timestamp_us += 20'000;
        auto delta = expect_ok(
            encode_delta(info, {removed, all, split.triangles, next_triangle_id}, encoding));
        session.frames.push_back(delta.bytes);
        next_triangle_id += split.triangles.size();
        sender.apply_split(chosen, std::move(split), delta.triangle_ids);
    }
    // A function change moves the vertices of a cap outward by 2%: the triangles around them
    // are removed and added again (new ids), carrying the vertices' new values.
    std::set<std::uint32_t> moved_ids;
    for (std::size_t t : cap(sender.mesh, {0, 0, -1}, 20)) {
        for (std::uint32_t v : sender.mesh.triangles[t].vertices) moved_ids.insert(v);
    }
    for (std::uint32_t v : moved_ids) sender.mesh.vertices[v].position *= 1.02f;  // id == index
    std::vector<std::size_t> touched;
    for (std::size_t t = 0; t < sender.mesh.triangles.size(); ++t) {
        const auto& corners = sender.mesh.triangles[t].vertices;
        if (std::any_of(corners.begin(), corners.end(),
                        [&](std::uint32_t v) { return moved_ids.contains(v); })) {
            touched.push_back(t);
        }
    }
    std::vector<std::uint64_t> replaced;
    for (std::size_t t : touched) replaced.push_back(sender.ids[t]);
    Subdivision same{{}, pick(sender.mesh, touched)};
    ++info.sequence;
    ++info.function_version;
    info.timestamp_us += 20'000;
    auto move = expect_ok(encode_delta(
        info, {replaced, sender.mesh.vertices, same.triangles, next_triangle_id}, encoding));
    session.frames.push_back(move.bytes);
    next_triangle_id += same.triangles.size();
    sender.apply_split(touched, std::move(same), move.triangle_ids);

    ++info.sequence;
    info.flags = frame_flags::converged;
    const std::vector<std::size_t> dropped = {3, 5, sender.ids.size() - 1};
    std::vector<std::uint64_t> removed;
    for (std::size_t i : dropped) removed.push_back(sender.ids[i]);
    session.frames.push_back(expect_ok(encode_delta(info, {removed, {}, {}, 0}, encoding)).bytes);
    sender.apply_split(dropped, {}, {});
    session.final_triangles = sender.sorted();
    return session;
}

}  // namespace isomesh::protocol::samples
