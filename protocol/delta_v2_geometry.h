// The arithmetic version-2 deltas share between encoder and decoders (PROTOCOL.md 4.5.3): the
// position grid (Draco's quantization formulas, so that a vertex decodes to the same floats from a
// keyframe's Draco payload and from a delta), octahedral normals, and the predictions of a split
// vertex from the edge it splits. Every step is an IEEE-754 double operation in a fixed order (no
// fused multiply-add: CMake compiles the protocol with -ffp-contract=off), so a JavaScript
// decoder computes the same integers (clients/js/src/delta_v2.js).
#pragma once

#include <array>
#include <cstdint>

#include <glm/vec3.hpp>

#include "protocol/mesh_codec.h"

namespace isomesh::protocol {

using GridPoint = std::array<std::int64_t, 3>;
using OctNormal = std::array<std::int64_t, 2>;

class GridMath {
  public:
    explicit GridMath(const QuantizationGrid& grid);
    /// The largest grid coordinate, 2^position_bits - 1.
    std::int64_t max_coordinate() const { return max_; }
    /// The largest octahedral coordinate magnitude, 2^(normal_bits - 1) - 1.
    std::int64_t max_octahedral() const { return octahedral_; }
    int position_bits() const { return grid_.position_bits; }
    int normal_bits() const { return grid_.normal_bits; }
    /// A position onto the grid: clamped into the cube, then Draco's quantization (float).
    GridPoint quantize(const glm::vec3& position) const;
    /// Draco's dequantization: q * (range / max) + origin, in float.
    glm::vec3 dequantize(const GridPoint& q) const;
    /// The grid point of a position already on the grid (exact: rounds away float error).
    GridPoint recover(const glm::vec3& position) const;
    OctNormal encode_normal(const glm::dvec3& normal) const;
    glm::vec3 decode_normal(const OctNormal& code) const;
    /// The predicted grid point of the vertex splitting the edge (p, q): the midpoint, bent along
    /// the ends' mean normal by the circular arc's sagitta ((p - q) . (np - nq) / 8).
    GridPoint predict_split(const GridPoint& p, const GridPoint& q, const glm::vec3& np,
                            const glm::vec3& nq) const;
    /// The predicted normal of that vertex: the octahedral code of np + nq.
    OctNormal predict_normal(const glm::vec3& np, const glm::vec3& nq) const;
    /// The predicted grid point of a held vertex (grid point p, normal n) that moved `steps` grid
    /// steps along its normal, as a surface moving with a parameter moves: p + n * steps, rounded
    /// and clamped per axis.
    GridPoint predict_move(const GridPoint& p, const glm::vec3& n, std::int64_t steps) const;
    bool valid(const GridPoint& q) const;
    bool valid(const OctNormal& n) const;

  private:
    QuantizationGrid grid_;
    std::int64_t max_;
    std::int64_t octahedral_;
    float delta_;
    float inverse_delta_;
};

}  // namespace isomesh::protocol
