// Mesh deltas: what changed in a refined mesh since the last step, in terms of stable ids.
//
// Every triangle and vertex a refiner creates gets an id that is never given to another triangle or
// vertex in the same session. A triangle id always denotes the same three vertex ids (a merge
// brings a split triangle back under its old id); a vertex keeps its id while it moves (when the
// function changes). Clients weld shared vertices by id.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include <glm/vec3.hpp>

#include "mesh/mesh.h"
#include "refine/huge_pages.h"

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

/// Accumulates changes as they happen and produces the net delta. Changes are logged in order and
/// netted per id when the delta is taken (by the first and last change of each id, found by
/// indexing the ids' range or by sorting: no hashing on the refiner's path).
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
    void reserve(std::size_t vertex_changes, std::size_t triangle_changes) {
        vertices_.reserve(vertex_changes);
        triangles_.reserve(triangle_changes);
    }
    /// The net delta since construction or the last take(); resets the builder. Preconditions
    /// (not checked): a vertex id is added at most once and not changed after its removal; a
    /// triangle id alternates between additions and removals.
    MeshDelta take();

  private:
    enum class Change : std::uint8_t { Added, Moved, Removed };
    struct VertexChange {
        Change change;
        DeltaVertex vertex;
    };
    struct TriangleChange {
        Change change;
        DeltaTriangle triangle;
    };
    /// The first and the last change of one id: indices into a log.
    using Run = std::array<std::uint32_t, 2>;
    static constexpr std::uint32_t kNoChange = ~std::uint32_t{0};
    template <typename Entry>
    void index_by_id(const HugePageVector<Entry>& log, std::uint32_t (*id_of)(const Entry&));
    /// Calls visit(run) for every id of the log last indexed, in increasing id order.
    template <typename Visit>
    void visit_runs(Visit visit) const;

    HugePageVector<VertexChange> vertices_;
    HugePageVector<TriangleChange> triangles_;
    // Scratch of take(), kept between calls: the runs by id (compact ids) or sorted keys.
    HugePageVector<Run> by_id_;
    std::vector<std::uint64_t> keys_;
};

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
