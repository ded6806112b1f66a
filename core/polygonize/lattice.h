// The integer lattice of the octree: every cell corner, at every depth, is a point of the finest
// lattice (2^max_depth cells per axis over the meshing box), named by its integer coordinates.
// Corner values and edge vertices are keyed by these coordinates, so a point is evaluated once
// whichever cell asks for it, and two cells sharing an edge share its vertex.
#pragma once

#include <cassert>
#include <cmath>
#include <cstdint>

#include <glm/vec3.hpp>

#include "eval/evaluator.h"

namespace isomesh {

/// Deepest octree supported: coordinates up to 2^16 fit the 17 bits per axis of a key.
inline constexpr int kMaxOctreeDepth = 16;

/// An octree cell: integer coordinates (0 .. 2^depth - 1 per axis) at its depth.
struct CellId {
    glm::u32vec3 coords{0};
    int depth = 0;

    CellId child(int octant) const {
        return {2u * coords + glm::u32vec3(octant & 1, (octant >> 1) & 1, (octant >> 2) & 1),
                depth + 1};
    }
    CellId parent() const { return {coords / 2u, depth - 1}; }
    /// The ancestor at `level` (<= depth).
    CellId ancestor(int level) const {
        const auto shift = static_cast<std::uint32_t>(depth - level);
        return {coords >> shift, level};
    }
    bool operator==(const CellId&) const = default;
};

/// Bits of v (up to 16) spread to every third bit.
inline std::uint64_t spread_bits3(std::uint32_t v) {
    std::uint64_t x = v & 0xffffu;
    x = (x | x << 16) & 0x0000ff0000ffull;
    x = (x | x << 8) & 0x00f00f00f00full;
    x = (x | x << 4) & 0x0c30c30c30c3ull;
    x = (x | x << 2) & 0x249249249249ull;
    return x;
}

/// The Morton (Z-order) code of p, x in the lowest bit: the order in which a depth-first walk of
/// the octree visits its cells (children in octant order).
inline std::uint64_t morton_code(const glm::u32vec3& p) {
    return spread_bits3(p.x) | spread_bits3(p.y) << 1 | spread_bits3(p.z) << 2;
}

/// A key ordering cells by depth, then in octree order within a depth (the order in which a
/// breadth-first walk classifies them); unique per cell.
inline std::uint64_t level_order_key(const CellId& cell) {
    return std::uint64_t(cell.depth) << 48 | morton_code(cell.coords);
}
inline CellId cell_of_level_order_key(std::uint64_t key) {
    CellId cell;
    cell.depth = static_cast<int>(key >> 48);
    for (int bit = 0; bit < cell.depth; ++bit) {
        for (int axis = 0; axis < 3; ++axis)
            cell.coords[axis] |= static_cast<std::uint32_t>((key >> (3 * bit + axis)) & 1u) << bit;
    }
    return cell;
}

class Lattice {
  public:
    /// Preconditions: box finite with lo < hi on every axis; 0 <= max_depth <= kMaxOctreeDepth.
    Lattice(const Box& box, int max_depth) : box_(box), max_depth_(max_depth) {
        assert(max_depth >= 0 && max_depth <= kMaxOctreeDepth);
    }

    const Box& box() const { return box_; }
    int max_depth() const { return max_depth_; }
    /// Finest lattice cells per axis.
    std::uint32_t resolution() const { return 1u << max_depth_; }

    /// The position of lattice point p (0 <= p <= resolution() per axis). std::lerp is exact at
    /// both ends, so points on the box's faces lie exactly on them.
    glm::dvec3 point(const glm::u32vec3& p) const {
        const double scale = std::ldexp(1.0, -max_depth_);
        glm::dvec3 result;
        for (int axis = 0; axis < 3; ++axis) {
            result[axis] = std::lerp(box_.lo[axis], box_.hi[axis], p[axis] * scale);
        }
        return result;
    }

    /// The lowest corner of `cell` in finest-lattice coordinates.
    glm::u32vec3 origin(const CellId& cell) const { return cell.coords << span_shift(cell); }
    /// The edge length of a cell at `depth`, in finest-lattice steps.
    std::uint32_t span(int depth) const { return 1u << (max_depth_ - depth); }
    /// Corner c (mc33.h numbering: offset (c & 1, (c >> 1) & 1, (c >> 2) & 1)) of `cell`.
    glm::u32vec3 corner(const CellId& cell, int c) const {
        return origin(cell) + span(cell.depth) * glm::u32vec3(c & 1, (c >> 1) & 1, (c >> 2) & 1);
    }

    /// The order of a depth-first walk of the octree, for cells that do not overlap: the Morton
    /// code of the cell's lowest corner on the finest lattice.
    std::uint64_t octree_order(const CellId& cell) const { return morton_code(origin(cell)); }

    Box cell_box(const CellId& cell) const {
        return {point(origin(cell)), point(origin(cell) + glm::u32vec3(span(cell.depth)))};
    }

    /// A unique 51-bit key of lattice point p.
    static std::uint64_t key(const glm::u32vec3& p) {
        return std::uint64_t{p.x} | std::uint64_t{p.y} << 17 | std::uint64_t{p.z} << 34;
    }
    static glm::u32vec3 unkey(std::uint64_t key) {
        constexpr std::uint64_t mask = (1u << 17) - 1;
        return {key & mask, (key >> 17) & mask, (key >> 34) & mask};
    }
    /// A unique key of the lattice edge from point `lower` along `axis` (the edge's length is
    /// implied by the depth of the cells using it).
    static std::uint64_t edge_key(const glm::u32vec3& lower, int axis) {
        return key(lower) | std::uint64_t(axis) << 51;
    }

  private:
    std::uint32_t span_shift(const CellId& cell) const {
        return static_cast<std::uint32_t>(max_depth_ - cell.depth);
    }

    Box box_;
    int max_depth_;
};

/// A corner or edge end is inside the surface when its value is < 0 (mc33.h's convention). NaN
/// (undefined) counts as outside.
inline bool is_inside(double value) {
    return value < 0.0;
}

}  // namespace isomesh
