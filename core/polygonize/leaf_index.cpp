#include "polygonize/leaf_index.h"

namespace isomesh {

std::uint64_t LeafIndex::key(const CellId& cell) {
    return Lattice::key(cell.coords) | std::uint64_t(cell.depth) << 51;
}

LeafIndex::LeafIndex(std::span<const CellId> leaves) {
    for (const CellId& leaf : leaves) {
        leaves_.insert(key(leaf));
        CellId ancestor = leaf;
        while (ancestor.depth > 0) {
            ancestor = {ancestor.coords / 2u, ancestor.depth - 1};
            if (!internal_.insert(key(ancestor)).second) break;  // its ancestors are in already
        }
    }
}

std::vector<CellId> LeafIndex::finer_across(const CellId& cell, int axis, int side) const {
    std::vector<CellId> out;
    const std::uint32_t n = 1u << cell.depth;
    if ((side == 0 && cell.coords[axis] == 0) || (side == 1 && cell.coords[axis] + 1 == n)) {
        return out;  // the face is on the box
    }
    CellId neighbour = cell;
    neighbour.coords[axis] = side == 0 ? cell.coords[axis] - 1 : cell.coords[axis] + 1;
    if (internal_.contains(key(neighbour))) collect_touching(neighbour, axis, 1 - side, out);
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
