// A session's mesh as its subscribers hold it, kept by the server to write frames.
//
// The refiner numbers triangles with ids of its own (a merge brings a triangle back under its old
// id); on the wire a delta's added triangles get fresh ids, base + decoded index (PROTOCOL.md), so
// this mirror maps each live refiner triangle to its wire id. A vertex that moved (a new function
// version) is re-sent as PROTOCOL.md says: the delta removes every live triangle around it and
// adds it again (under a new wire id), the payload carrying the vertex's new values.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "mesh/mesh.h"
#include "protocol/held_mesh.h"
#include "protocol/mesh_codec.h"
#include "refine/mesh_delta.h"

namespace isomesh::server {

/// The contents of one delta frame, before encoding.
struct WireDelta {
    std::vector<std::uint64_t> removed;         ///< wire ids, ascending
    std::vector<protocol::Vertex> vertices;     ///< every vertex the added triangles use
    std::vector<protocol::Triangle> triangles;  ///< added
    std::vector<std::uint32_t> refiner_ids;     ///< refiner id of each added triangle
    bool empty() const { return removed.empty() && triangles.empty(); }
};

/// The contents of a keyframe: the whole mesh, triangles in ascending wire id order.
struct KeyframeContent {
    std::vector<protocol::Vertex> vertices;
    std::vector<protocol::Triangle> triangles;
    std::vector<std::uint64_t> wire_ids;
};

/// The mesh as the refiner numbers it (for building another wire mirror from this one).
struct RefinerMesh {
    std::vector<protocol::Vertex> vertices;                               ///< refiner vertex ids
    std::vector<std::pair<std::uint32_t, protocol::Triangle>> triangles;  ///< by refiner id
};

class WireMesh {
  public:
    /// Replaces everything by `mesh`, whose triangle i has refiner id triangle_ids[i] and vertex v
    /// vertex id vertex_ids[v]; wire ids are assigned from next_wire_id() on, in triangle order.
    void reset(const Mesh& mesh, std::span<const std::uint32_t> triangle_ids,
               std::span<const std::uint32_t> vertex_ids);

    /// Applies a refiner delta and returns what the frame must carry. The added triangles get
    /// their wire ids from commit_wire_ids once the frame is encoded.
    /// Precondition: `delta` applies to this mesh (DeltaMesh::apply would succeed).
    WireDelta apply(const MeshDelta& delta);

    /// Applies a refiner delta for which no version-1 frame is made (no version-1 subscriber: the
    /// next one gets a keyframe first): added triangles get wire ids from next_wire_id() on, moved
    /// vertices keep their triangles' ids. True when the delta changes a triangle or a vertex a
    /// triangle uses (what a frame would show).
    /// Precondition: `delta` applies to this mesh.
    bool follow(const MeshDelta& delta);

    /// Records the wire ids the encoder gave to the triangles of the last apply() (wire_ids[i]
    /// for content.refiner_ids[i]) and advances next_wire_id() past them.
    void commit_wire_ids(std::span<const std::uint32_t> refiner_ids,
                         std::span<const std::uint64_t> wire_ids);

    KeyframeContent keyframe() const;
    /// The mesh in refiner ids, triangles ascending by refiner id.
    RefinerMesh refiner_mesh() const;

    std::uint64_t next_wire_id() const { return next_wire_id_; }
    std::size_t triangle_count() const { return triangles_.size(); }
    std::size_t vertex_count() const { return vertices_.size(); }

  private:
    struct LiveTriangle {
        std::array<std::uint32_t, 3> vertices;
        std::uint64_t wire_id;
    };
    static constexpr std::uint64_t kUnassigned = ~std::uint64_t{0};

    protocol::IdTable<std::uint32_t, LiveTriangle> triangles_;  // by refiner id
    protocol::IdTable<std::uint32_t, protocol::Vertex> vertices_;
    std::uint64_t next_wire_id_ = 0;
};

}  // namespace isomesh::server
