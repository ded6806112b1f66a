// Which octree leaves lie across a face of a leaf: the neighbour queries of crack patching and
// grading. Updated in place as leaves are split, so that meshing a frontier that is split again
// and again (polygonizer.cpp, step 4) does not index every leaf each time.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "polygonize/id_tables.h"
#include "polygonize/lattice.h"

namespace isomesh {

class LeafIndex {
  public:
    /// Precondition: the leaves do not overlap.
    explicit LeafIndex(std::span<const CellId> leaves);

    /// Leaf `cell` is replaced by `leaves`, the leaves of its subtree (possibly none: the cell
    /// turned out to hold no surface).
    void replace(const CellId& cell, std::span<const CellId> leaves);

    /// The leaves smaller than `cell` on the other side of its face orthogonal to `axis` (side 0:
    /// the low face, 1: the high face) that touch the face, in octree order. Empty when the other
    /// side is one leaf of the same size or a larger leaf, holds no leaf, or is outside the box.
    std::vector<CellId> finer_across(const CellId& cell, int axis, int side) const;

    /// Every leaf sharing part of a face with `cell` from outside it, whatever its size (`cell`
    /// need not be a leaf), face by face; a leaf may appear more than once.
    std::vector<CellId> face_neighbours(const CellId& cell) const;

  private:
    static std::uint64_t key(const CellId& cell);
    void insert(const CellId& leaf);
    void collect_touching(const CellId& cell, int axis, int side, std::vector<CellId>& out) const;

    IdSet leaves_;
    IdSet internal_;  // proper ancestors of leaves
};

}  // namespace isomesh
