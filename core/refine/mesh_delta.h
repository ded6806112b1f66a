// Mesh deltas: what changed in a refined mesh since the last step, in terms of stable ids.
//
// Every triangle and vertex a refiner creates gets an id that is never given to another triangle or
// vertex in the same session. A triangle id always denotes the same three vertex ids (a merge
// brings a split triangle back under its old id); a vertex keeps its id while it moves (when the
// function changes). Clients weld shared vertices by id.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include <glm/vec3.hpp>

#include "mesh/mesh.h"
#include "refine/array_memory.h"

namespace isomesh {

struct DeltaVertex {
    std::uint32_t id = 0;
    glm::dvec3 position{0.0};
    glm::dvec3 normal{0.0};
};

struct DeltaTriangle {
    std::uint32_t id = 0;
    std::array<std::uint32_t, 3> vertices{};  // vertex ids, counter-clockwise seen from f > 0
};

/// Applied in member order: removals, then vertex additions and moves, then triangle additions.
/// Each list is sorted by id and holds an id at most once; a delta never adds and removes the same
/// id (such pairs cancel out when the delta is built).
struct MeshDelta {
    std::vector<std::uint32_t> removed_triangles;
    std::vector<std::uint32_t> removed_vertices;  // no longer used by any triangle
    std::vector<DeltaVertex> added_vertices;
    std::vector<DeltaVertex> moved_vertices;  // new position and normal of an existing vertex
    std::vector<DeltaTriangle> added_triangles;

    bool empty() const {
        return removed_triangles.empty() && removed_vertices.empty() && added_vertices.empty() &&
               moved_vertices.empty() && added_triangles.empty();
    }
};

/// The first and the last change of every id of a log of changes, in increasing id order: what a
/// stable sort by id followed by a scan of each run of equal ids gives, without the sort where the
/// ids are compact (no hashing on the refiner's path). Shared by the two delta logs below.
class IdRuns {
  public:
    /// Log indices of an id's first and last change.
    using Run = std::array<std::uint32_t, 2>;
    /// Indexes `log` by id_of(entry).
    template <typename Log, typename IdOf>
    void index(const Log& log, IdOf id_of);
    /// Calls visit(run) for every id of the log last indexed, in increasing id order.
    template <typename Visit>
    void visit(Visit visit) const;

  private:
    static constexpr std::uint32_t kNoChange = ~std::uint32_t{0};
    // The runs by id (compact ids: by_id_[id - lo]) or sorted (id, index) keys.
    RecycledVector<Run> by_id_;
    std::vector<std::uint64_t> keys_;
};

enum class DeltaChange : std::uint8_t { Added, Moved, Removed };

/// The net delta of a vertex log and a triangle log (entries with a `change`), given each
/// entry's id (id_of) and data (vertex_of, triangle_of: read only for the changes that remain).
template <typename VertexLog, typename TriangleLog, typename IdOf, typename VertexOf,
          typename TriangleOf>
MeshDelta net_delta(const VertexLog& vertices, const TriangleLog& triangles, IdRuns& runs,
                    IdOf id_of, VertexOf vertex_of, TriangleOf triangle_of);

/// Accumulates changes as they happen and produces the net delta. Changes are logged in order and
/// netted per id when the delta is taken (by the first and last change of each id: IdRuns).
class DeltaBuilder {
  public:
    void add_vertex(const DeltaVertex& vertex) { vertices_.push_back({Change::Added, vertex}); }
    void move_vertex(const DeltaVertex& vertex) { vertices_.push_back({Change::Moved, vertex}); }
    void remove_vertex(std::uint32_t id) { vertices_.push_back({Change::Removed, {id, {}, {}}}); }
    void add_triangle(const DeltaTriangle& triangle) {
        triangles_.push_back({Change::Added, triangle});
    }
    void remove_triangle(std::uint32_t id) { triangles_.push_back({Change::Removed, {id, {}}}); }
    /// Room for this many changes logged at once.
    void reserve(Reservation vertex_changes, Reservation triangle_changes) {
        isomesh::reserve(vertices_, vertex_changes);
        isomesh::reserve(triangles_, triangle_changes);
    }
    /// The net delta since construction or the last take(); resets the builder. Preconditions
    /// (not checked): a vertex id is added at most once and not changed after its removal; a
    /// triangle id alternates between additions and removals.
    MeshDelta take();

  private:
    using Change = DeltaChange;
    struct VertexChange {
        Change change;
        DeltaVertex vertex;
    };
    struct TriangleChange {
        Change change;
        DeltaTriangle triangle;
    };

    RecycledVector<VertexChange> vertices_;
    RecycledVector<TriangleChange> triangles_;
    IdRuns runs_;  // scratch of take(), kept between calls
};

/// DeltaBuilder for an owner that keeps every vertex and triangle in a slot and can tell their
/// current data from the slot when the delta is taken (the refiner): a change logs an id and a
/// slot, 12 bytes, where DeltaBuilder copies the data (20 bytes a triangle, 64 a vertex). The net
/// delta is the same: a vertex added or moved, and not removed since, is in its slot with the
/// data of its last change; a triangle added and not removed since is in its slot.
class SlotDeltaLog {
  public:
    void add_vertex(std::uint32_t id, std::uint32_t slot) { log_vertex({id, slot, Change::Added}); }
    void move_vertex(std::uint32_t id, std::uint32_t slot) {
        log_vertex({id, slot, Change::Moved});
    }
    void remove_vertex(std::uint32_t id) { log_vertex({id, 0, Change::Removed}); }
    void add_triangle(std::uint32_t id, std::uint32_t slot) {
        log_triangle({id, slot, Change::Added});
    }
    void remove_triangle(std::uint32_t id) { log_triangle({id, 0, Change::Removed}); }
    void reserve(Reservation vertex_changes, Reservation triangle_changes) {
        vertices_wanted_ = isomesh::reserve(vertices_, vertex_changes);
        triangles_wanted_ = isomesh::reserve(triangles_, triangle_changes);
    }
    /// Forgets the changes logged so far.
    void clear() {
        vertices_.clear();
        triangles_.clear();
    }
    /// The net delta since the last take() or clear(), with vertex_at(slot) -> DeltaVertex and
    /// triangle_at(slot) -> DeltaTriangle, the current data in a slot; resets the log.
    /// Preconditions as DeltaBuilder::take's.
    template <typename VertexAt, typename TriangleAt>
    MeshDelta take(VertexAt vertex_at, TriangleAt triangle_at);

  private:
    using Change = DeltaChange;
    struct Entry {
        std::uint32_t id;
        std::uint32_t slot;
        Change change;
    };

    void log_vertex(const Entry& e) {
        make_room(vertices_, vertices_.size() + 1, vertices_wanted_);
        vertices_.push_back(e);
    }
    void log_triangle(const Entry& e) {
        make_room(triangles_, triangles_.size() + 1, triangles_wanted_);
        triangles_.push_back(e);
    }

    RecycledVector<Entry> vertices_;
    RecycledVector<Entry> triangles_;
    std::size_t vertices_wanted_ = 0;  // the room reserved for (make_room)
    std::size_t triangles_wanted_ = 0;
    IdRuns runs_;
};

// ---------------------------------------------------------------------------------------------
// Templates

template <typename Log, typename IdOf>
void IdRuns::index(const Log& log, IdOf id_of) {
    by_id_.clear();
    keys_.clear();
    if (log.empty()) return;
    std::uint32_t lo = id_of(log[0]), hi = lo;
    for (const auto& c : log) {
        lo = std::min(lo, id_of(c));
        hi = std::max(hi, id_of(c));
    }
    // Compact ids (they are: ids are given in sequence, and a step changes mostly recent ones):
    // by_id_[id - lo] holds the id's run.
    const std::size_t range = std::size_t{hi} - lo + 1;
    if (range <= 4 * log.size() + 1024) {
        by_id_.assign(range, Run{kNoChange, kNoChange});
        for (std::uint32_t i = 0; i < log.size(); ++i) {
            Run& run = by_id_[id_of(log[i]) - lo];
            if (run[0] == kNoChange) run[0] = i;
            run[1] = i;
        }
        return;
    }
    // Sparse ids: sort (id, index) keys; they are unique, so the order is the stable one.
    for (std::uint32_t i = 0; i < log.size(); ++i)
        keys_.push_back(std::uint64_t{id_of(log[i])} << 32 | i);
    std::sort(keys_.begin(), keys_.end());
}

template <typename Visit>
void IdRuns::visit(Visit visit) const {
    for (const Run& run : by_id_)
        if (run[0] != kNoChange) visit(run);
    for (std::size_t i = 0; i < keys_.size();) {
        std::size_t j = i + 1;
        while (j < keys_.size() && keys_[j] >> 32 == keys_[i] >> 32) ++j;
        visit(Run{static_cast<std::uint32_t>(keys_[i]), static_cast<std::uint32_t>(keys_[j - 1])});
        i = j;
    }
}

template <typename VertexLog, typename TriangleLog, typename IdOf, typename VertexOf,
          typename TriangleOf>
MeshDelta net_delta(const VertexLog& vertices, const TriangleLog& triangles, IdRuns& runs,
                    IdOf id_of, VertexOf vertex_of, TriangleOf triangle_of) {
    using Run = IdRuns::Run;
    using Change = DeltaChange;
    MeshDelta delta;
    // Net vertex changes: added (then maybe moved) -> added at its last place, unless removed;
    // moved -> moved to its last place, unless removed; removed -> removed.
    enum VertexList { kRemovedVertex, kAddedVertex, kMovedVertex, kNoVertexChange };
    runs.index(vertices, id_of);
    const auto vertex_list = [&](const Run& run) {
        const Change first = vertices[run[0]].change;
        if (vertices[run[1]].change == Change::Removed)
            return first != Change::Added ? kRemovedVertex : kNoVertexChange;
        return first == Change::Added ? kAddedVertex : kMovedVertex;
    };
    std::array<std::size_t, 4> counts{};
    runs.visit([&](const Run& run) { ++counts[vertex_list(run)]; });
    delta.removed_vertices.reserve(counts[kRemovedVertex]);
    delta.added_vertices.reserve(counts[kAddedVertex]);
    delta.moved_vertices.reserve(counts[kMovedVertex]);
    runs.visit([&](const Run& run) {
        switch (vertex_list(run)) {
            case kRemovedVertex:
                delta.removed_vertices.push_back(id_of(vertices[run[0]]));
                break;
            case kAddedVertex:
                delta.added_vertices.push_back(vertex_of(vertices[run[1]]));
                break;
            case kMovedVertex:
                delta.moved_vertices.push_back(vertex_of(vertices[run[1]]));
                break;
            default:
                break;
        }
    });
    // Net triangle changes: an id always names the same vertices, so only the first and the last
    // change matter (add..add: added; remove..remove: removed; otherwise no change).
    runs.index(triangles, id_of);
    counts = {};
    runs.visit([&](const Run& run) {
        if (triangles[run[0]].change == triangles[run[1]].change)
            ++counts[triangles[run[0]].change == Change::Added ? 0 : 1];
    });
    delta.added_triangles.reserve(counts[0]);
    delta.removed_triangles.reserve(counts[1]);
    runs.visit([&](const Run& run) {
        const auto& first = triangles[run[0]];
        if (first.change != triangles[run[1]].change) return;
        if (first.change == Change::Added)
            delta.added_triangles.push_back(triangle_of(first));
        else
            delta.removed_triangles.push_back(id_of(first));
    });
    return delta;
}

template <typename VertexAt, typename TriangleAt>
MeshDelta SlotDeltaLog::take(VertexAt vertex_at, TriangleAt triangle_at) {
    MeshDelta delta = net_delta(
        vertices_, triangles_, runs_, [](const Entry& e) { return e.id; },
        [&](const Entry& e) { return vertex_at(e.slot); },
        [&](const Entry& e) { return triangle_at(e.slot); });
    clear();
    return delta;
}

/// A mesh keyed by ids, built by applying deltas in order (what a client holds).
class DeltaMesh {
  public:
    /// Applies `delta`; on an inconsistency (removing an unknown id, adding a known one, a triangle
    /// using an unknown vertex, removing a vertex still in use) returns a description and leaves
    /// the mesh partly updated. Returns an empty string on success.
    std::string apply(const MeshDelta& delta);

    std::size_t vertex_count() const { return vertices_.size(); }
    std::size_t triangle_count() const { return triangles_.size(); }
    /// The mesh with vertices and triangles sorted by id (no neighbours).
    Mesh to_mesh() const;
    /// The triangle ids in increasing order (the order of to_mesh().triangles).
    std::vector<std::uint32_t> triangle_ids() const;

  private:
    std::unordered_map<std::uint32_t, DeltaVertex> vertices_;
    std::unordered_map<std::uint32_t, DeltaTriangle> triangles_;
    std::unordered_map<std::uint32_t, std::uint32_t> uses_;  // vertex id -> triangles using it
};

}  // namespace isomesh
