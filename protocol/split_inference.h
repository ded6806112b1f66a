// Which edge each new vertex of a net delta split (for the version-2 encoder, delta_v2.h).
//
// The refiner bisects with newest vertex bisection (core/refine/refiner.h): a split of the edge
// (p, q) replaces the triangles (p, q, r) and (q, p, s) by (p, m, r), (m, q, r), (q, m, s) and
// (m, p, s). A net delta lists only the vertices and triangles it ends with, so the splits are
// recovered backwards: the newest vertex's star is its split's two or four children; undoing it
// brings back the parents, and so on down to the oldest new vertex. A star of four has two
// readings (either diagonal of its ring may be the split edge); the parents' newest corners pick
// one (a triangle made by a split has its newest vertex opposite its base edge), and the longer
// diagonal breaks ties (a phase-1 triangle's base edge is its longest). A vertex whose star fits
// neither shape is left to be sent explicitly.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include <glm/vec3.hpp>

#include "protocol/mesh_codec.h"

namespace isomesh::protocol {

struct InferredSplit {
    std::uint32_t vertex = 0;
    std::uint32_t p = 0;  ///< the split edge's ends
    std::uint32_t q = 0;
};

struct SplitInference {
    std::vector<InferredSplit> splits;  ///< ascending by vertex
    std::vector<std::uint32_t> loose;   ///< new vertices no split explains, ascending
};

/// `new_vertices` ascending in creation order; `added` the delta's added triangles; `position`
/// gives any vertex's position (for ties).
SplitInference infer_splits(std::span<const std::uint32_t> new_vertices,
                            std::span<const Triangle> added,
                            const std::function<glm::vec3(std::uint32_t)>& position);

}  // namespace isomesh::protocol
