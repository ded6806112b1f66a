#include "polygonize/leaf_index.h"

#include <cassert>

namespace isomesh {
namespace {

/// The cell of `cell`'s size across its face (axis, side), or false at the box.
bool across(const CellId& cell, int axis, int side, CellId& neighbour) {
    const std::uint32_t n = 1u << cell.depth;
    if ((side == 0 && cell.coords[axis] == 0) || (side == 1 && cell.coords[axis] + 1 == n)) {
        return false;
    }
    neighbour = cell;
    neighbour.coords[axis] = side == 0 ? cell.coords[axis] - 1 : cell.coords[axis] + 1;
    return true;
}

}  // namespace

std::uint64_t LeafIndex::key(const CellId& cell) {
    return Lattice::key(cell.coords) | std::uint64_t(cell.depth) << 51;
}

LeafIndex::LeafIndex(std::span<const CellId> leaves) {
    for (const CellId& leaf : leaves) insert(leaf);
}

void LeafIndex::insert(const CellId& leaf) {
    leaves_.insert(key(leaf));
    CellId ancestor = leaf;
    while (ancestor.depth > 0) {
        ancestor = ancestor.parent();
        if (!internal_.insert(key(ancestor)).second) break;  // its ancestors are in already
    }
}

void LeafIndex::replace(const CellId& cell, std::span<const CellId> leaves) {
    [[maybe_unused]] const std::size_t erased = leaves_.erase(key(cell));
    assert(erased == 1);
    for (const CellId& leaf : leaves) {
        assert(leaf.depth > cell.depth && leaf.ancestor(cell.depth) == cell);
        insert(leaf);
    }
}

std::vector<CellId> LeafIndex::finer_across(const CellId& cell, int axis, int side) const {
    std::vector<CellId> out;
    CellId neighbour;
    if (!across(cell, axis, side, neighbour)) return out;  // the face is on the box
    if (internal_.contains(key(neighbour))) collect_touching(neighbour, axis, 1 - side, out);
    return out;
}

std::vector<CellId> LeafIndex::face_neighbours(const CellId& cell) const {
    std::vector<CellId> out;
    for (int axis = 0; axis < 3; ++axis) {
        for (int side = 0; side < 2; ++side) {
            CellId neighbour;
            if (!across(cell, axis, side, neighbour)) continue;
            if (internal_.contains(key(neighbour))) {
                collect_touching(neighbour, axis, 1 - side, out);
                continue;
            }
            // The leaf of the neighbour's size or larger that holds it, if any: the first
            // indexed ancestor; an internal one means the neighbour is an empty cell.
            for (CellId a = neighbour;; a = a.parent()) {
                if (leaves_.contains(key(a))) {
                    out.push_back(a);
                    break;
                }
                if (a.depth == 0 || (a != neighbour && internal_.contains(key(a)))) break;
            }
        }
    }
    return out;
}

/// The leaves inside internal cell `cell` touching its face (axis, side).
void LeafIndex::collect_touching(const CellId& cell, int axis, int side,
                                 std::vector<CellId>& out) const {
    for (int octant = 0; octant < 8; ++octant) {
        if (((octant >> axis) & 1) != side) continue;
        const CellId child = cell.child(octant);
        if (leaves_.contains(key(child))) {
            out.push_back(child);
        } else if (internal_.contains(key(child))) {
            collect_touching(child, axis, side, out);
        }
    }
}

}  // namespace isomesh
