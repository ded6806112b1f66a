// Synthetic meshes for the protocol's tests, sample frames and fuzz corpora: an icosphere with
// global vertex ids, caps of it, and a refinement-like delta (each triangle of a cap replaced by
// four, midpoints projected on the sphere). Not part of the protocol library.
#pragma once

#include <cstdint>
#include <vector>

#include "protocol/frame.h"
#include "protocol/mesh_codec.h"

namespace isomesh::protocol::samples {

struct SampleMesh {
    std::vector<Vertex> vertices;     ///< vertices[i].id == first_id + i
    std::vector<Triangle> triangles;  ///< counter-clockwise seen from outside
};

/// A unit-radius-`radius` icosphere with 20 * 4^subdivisions triangles, vertex ids from first_id.
SampleMesh icosphere(int subdivisions, float radius = 1.0f, std::uint32_t first_id = 0);

/// Indices of the `count` triangles whose centroids lie closest to the ray through `direction`.
std::vector<std::size_t> cap(const SampleMesh& mesh, glm::vec3 direction, std::size_t count);

/// The triangles at `indices`.
std::vector<Triangle> pick(const SampleMesh& mesh, const std::vector<std::size_t>& indices);

struct Subdivision {
    std::vector<Vertex> vertices;     ///< the new midpoint vertices only
    std::vector<Triangle> triangles;  ///< 4 per subdivided triangle
};

/// Splits each triangle at `indices` into four; midpoints get ids from `first_new_id` (a midpoint
/// shared by two subdivided triangles is created once) and are pushed to the sphere of `radius`.
Subdivision subdivide(const SampleMesh& mesh, const std::vector<std::size_t>& indices,
                      std::uint32_t first_new_id, float radius = 1.0f);

/// The frames of a refining sphere as a server would send them: a keyframe of an icosphere with
/// non-consecutive triangle ids, three deltas each splitting a cap 1-to-4, a delta that moves
/// vertices (function version 2) by re-sending the triangles around them, and a delta that only
/// removes triangles (flagged converged). `final_triangles`: the sender's mesh after the last
/// frame, sorted by id.
struct SampleSession {
    std::vector<std::vector<std::uint8_t>> frames;
    std::vector<FrameTriangle> final_triangles;
};
SampleSession refining_sphere_session();

SessionId sample_session_id();

}  // namespace isomesh::protocol::samples
