// What the version-2 delta encoder (delta_v2.cpp) and decoder (delta_v2_decoder.cpp) share: the
// adaptive models of a body, the predicted split edge, and the overlay on which both replay a
// delta over the held mesh. Internal to the protocol library.
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <absl/container/flat_hash_set.h>

#include "protocol/delta_v2.h"
#include "protocol/delta_v2_geometry.h"
#include "protocol/range_coder.h"

namespace isomesh::protocol::delta_v2_detail {

using Corners = HeldMesh::Corners;

inline Error frame_error(std::string message) {
    return Error{ErrorCode::bad_frame, std::move(message)};
}
inline Error field_error(std::string message) {
    return Error{ErrorCode::bad_field, std::move(message)};
}

/// The adaptive contexts of a delta body; encoder and decoder start from the same state.
struct Models {
    IntModel count;
    IntModel split_gap;
    BitModel edge_mispredicted;
    BitModel edge_second;
    IntModel position;
    IntModel normal;
    IntModel removed_gap;
    IntModel vertex_step;
    IntModel moved_gap;
    IntModel moved_offset;
    IntModel moved_position;
    IntModel moved_normal;
};

/// The edge a split most likely bisects: the one opposite the triangle's newest (largest id)
/// corner, the base edge of newest vertex bisection. Edge e joins corners e and e + 1.
inline int predicted_edge(const Corners& c) {
    const int newest = c[0] > c[1] ? (c[0] > c[2] ? 0 : 2) : (c[1] > c[2] ? 1 : 2);
    return (newest + 1) % 3;
}

/// The client's mesh as a delta changes it: the held mesh with changes on top, copied per vertex
/// star on first touch. The encoder and the decoder run the same operations on it.
class Overlay {
  public:
    explicit Overlay(const HeldMesh& held) : held_(held) {}

    const Corners* triangle(std::uint64_t id) const {
        if (auto it = created_.find(id); it != created_.end()) return &it->second;
        if (removed_.contains(id)) return nullptr;
        return held_.triangle(id);
    }
    const Vertex* vertex(std::uint32_t id) const {
        if (auto it = vertices_.find(id); it != vertices_.end()) return &it->second;
        return held_.vertex(id);
    }
    std::span<const std::uint64_t> star(std::uint32_t v) const {
        if (auto it = stars_.find(v); it != stars_.end()) return it->second;
        return held_.star(v);
    }
    /// The triangle holding the directed edge p -> q, if any; where several do (a non-manifold
    /// edge), the one with the smallest id, whatever the order of the star.
    std::optional<std::uint64_t> holding(std::uint32_t p, std::uint32_t q) const {
        std::optional<std::uint64_t> found;
        for (std::uint64_t id : star(p)) {
            const Corners& c = *triangle(id);
            for (int k = 0; k < 3; ++k) {
                if (c[k] == p && c[(k + 1) % 3] == q && (!found || id < *found)) found = id;
            }
        }
        return found;
    }
    void remove(std::uint64_t id) {
        const Corners c = *triangle(id);
        for (std::uint32_t v : c) std::erase(star_mut(v), id);
        if (created_.erase(id) == 0) removed_.insert(id);
    }
    void add(std::uint64_t id, const Corners& c) {
        created_.emplace(id, c);
        for (std::uint32_t v : c) star_mut(v).push_back(id);
    }
    void set_vertex(const Vertex& v) { vertices_[v.id] = v; }
    /// Room for `n` more vertex values (a frame that moves every vertex sets tens of thousands),
    /// at most as many as the held mesh has.
    void reserve_vertices(std::size_t n) {
        vertices_.reserve(vertices_.size() + std::min(n, held_.vertex_count()));
    }
    /// Whether triangle `id` was held or made in this frame (ids are never reused).
    bool used(std::uint64_t id) const { return created_.contains(id) || held_.triangle(id); }

    /// Bisects edge e of triangle t (and the triangle across it) at the new vertex v: (p, q, r)
    /// becomes (p, v, r) and (v, q, r); (q, p, s) becomes (q, v, s) and (v, p, s). The halves get
    /// ids from next_id on, in that order.
    void split(std::uint64_t t, int e, std::uint32_t v, std::uint64_t& next_id) {
        const Corners c = *triangle(t);
        const std::uint32_t p = c[e], q = c[(e + 1) % 3], r = c[(e + 2) % 3];
        const std::optional<std::uint64_t> across = holding(q, p);
        remove(t);
        add(next_id++, {p, v, r});
        add(next_id++, {v, q, r});
        if (!across) return;
        const Corners d = *triangle(*across);
        const int k = d[0] == q ? 0 : d[1] == q ? 1 : 2;
        const std::uint32_t s = d[(k + 2) % 3];
        remove(*across);
        add(next_id++, {q, v, s});
        add(next_id++, {v, p, s});
    }

    /// What the client ends with: held triangles removed, the live triangles made, and the values
    /// of every vertex those use and of `moved`.
    DecodedFrame result(const FrameHeader& header, std::span<const std::uint32_t> moved) const {
        DecodedFrame out;
        out.header = header;
        out.removed.assign(removed_.begin(), removed_.end());
        std::sort(out.removed.begin(), out.removed.end());
        for (const auto& [id, c] : created_) out.triangles.push_back({id, c});
        std::sort(out.triangles.begin(), out.triangles.end(),
                  [](const FrameTriangle& a, const FrameTriangle& b) { return a.id < b.id; });
        absl::flat_hash_set<std::uint32_t> listed;
        listed.reserve(3 * out.triangles.size() + moved.size());
        out.vertices.reserve(listed.bucket_count());
        auto list = [&](std::uint32_t id) {
            if (listed.insert(id).second) out.vertices.push_back(*vertex(id));
        };
        for (const FrameTriangle& t : out.triangles) {
            for (std::uint32_t v : t.vertices) list(v);
        }
        for (std::uint32_t v : moved) list(v);
        out.header.removed_count = static_cast<std::uint32_t>(out.removed.size());
        out.header.triangle_count = static_cast<std::uint32_t>(out.triangles.size());
        return out;
    }

    /// The triangles made (and still live), in no particular order.
    const IdTable<std::uint64_t, Corners>& created() const { return created_; }
    /// The held triangles removed, in no particular order.
    const absl::flat_hash_set<std::uint64_t>& removed() const { return removed_; }

  private:
    std::vector<std::uint64_t>& star_mut(std::uint32_t v) {
        auto [it, added] = stars_.try_emplace(v);
        if (added) {
            const auto held = held_.star(v);
            it->second.assign(held.begin(), held.end());
        }
        return it->second;
    }

    const HeldMesh& held_;
    IdTable<std::uint64_t, Corners> created_;
    absl::flat_hash_set<std::uint64_t> removed_;
    IdTable<std::uint32_t, std::vector<std::uint64_t>> stars_;
    IdTable<std::uint32_t, Vertex> vertices_;
};

}  // namespace isomesh::protocol::delta_v2_detail
