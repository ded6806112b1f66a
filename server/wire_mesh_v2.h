// A session's mesh as its version-2 subscribers hold it (PROTOCOL.md 4.5), kept by the server to
// write version-2 frames once per session: the held mesh in wire ids (what the encoder predicts
// from, exactly as the clients do), and the maps from the refiner's triangle and vertex ids to
// wire ids. Version 2 numbers vertices too: a delta's new vertices get consecutive ids in the
// order the frame gives them, so that the frame need not name them.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "protocol/delta_v2.h"
#include "protocol/held_mesh.h"
#include "refine/mesh_delta.h"
#include "server/wire_mesh.h"

namespace isomesh::server {

class WireMeshV2 {
  public:
    /// Replaces everything by `mesh` (what a keyframe for every subscriber shows) under fresh
    /// wire ids, with positions and normals as the clients decode them on `grid`.
    void reset(const RefinerMesh& mesh, const protocol::QuantizationGrid& grid);

    /// Encodes the frame for a refiner delta (precondition: valid(), the delta applies) and
    /// advances the mirror to what the clients will hold.
    protocol::Result<protocol::EncodedDeltaV2> encode(const protocol::FrameInfo& info,
                                                      const MeshDelta& delta);

    /// The held mesh, triangles in ascending wire id order (a keyframe for one subscriber).
    KeyframeContent keyframe() const;

    /// True from reset() until a frame is made from the mirror: no client holds its ids yet, so
    /// the first keyframe may number the triangles in Draco's decoded order (no id section).
    bool renumberable() const { return renumberable_; }
    /// The first triangle id a renumbering may use.
    std::uint64_t next_triangle_id() const { return next_triangle_; }
    /// Gives triangle `from[i]` the id `to[i]` (ids from next_triangle_id() on); precondition:
    /// renumberable(), `from` lists every triangle.
    void renumber(std::span<const std::uint64_t> from, std::span<const std::uint64_t> to);
    /// A frame was made from the mirror: its ids are now the clients'.
    void sent() {
        commit();
        renumberable_ = false;
    }

    /// False after invalidate(): frames went out that this mirror did not follow (no version-2
    /// subscriber then), so the next version-2 keyframe must come from reset().
    bool valid() const { return valid_; }
    void invalidate() { valid_ = false; }
    std::size_t triangle_count() const {
        return staged_ ? staged_->content.triangles.size() : held_.triangle_count();
    }

  private:
    /// reset()'s mesh before it goes into held_: a first keyframe renumbers its triangles, so it is
    /// built once, under the final ids (a session's first frame is most of its first turn).
    struct Staged {
        protocol::DecodedFrame content;       ///< triangle i: id first_id + i
        std::vector<std::uint32_t> refiners;  ///< refiner id of triangle i
        std::uint64_t first_id = 0;
    };
    /// Puts the staged mesh into held_ under its ids.
    void commit();

    std::optional<Staged> staged_;
    protocol::HeldMesh held_;
    protocol::QuantizationGrid grid_;
    protocol::IdTable<std::uint32_t, std::uint64_t> triangle_of_;  // refiner -> wire
    protocol::IdTable<std::uint64_t, std::uint32_t> refiner_of_;   // wire -> refiner
    protocol::IdTable<std::uint32_t, std::uint32_t> vertex_of_;    // refiner -> wire
    std::uint64_t next_triangle_ = 0;
    std::uint32_t next_vertex_ = 0;
    bool valid_ = false;
    bool renumberable_ = false;
};

}  // namespace isomesh::server
