// Generation of the MC33 loop tables (see mc33_tables.h).
//
// On a face, walking its boundary counter-clockwise (seen from inside the cell), an edge whose
// corners go inside -> outside starts a contour segment and an edge going outside -> inside ends
// one; the segment keeps the inside corner on its left. A face with two crossed edges has one
// segment. An ambiguous face (four crossed edges) pairs each start with the next end when its
// inside corners are joined (the segments cut off the outside corners) and with the previous end
// otherwise (they cut off the inside corners). Every crossed edge starts a segment on one of its
// two faces and ends one on the other, so following segments traces closed loops.
#include "polygonize/mc33_tables.h"

#include <algorithm>
#include <bit>
#include <cassert>
#include <vector>

#include "polygonize/mc33.h"

namespace isomesh::mc33 {
namespace {

bool inside(std::uint8_t config, std::uint8_t corner) {
    return (config >> corner) & 1u;
}

struct UnionFind {
    std::array<std::uint8_t, 8> parent{0, 1, 2, 3, 4, 5, 6, 7};
    std::uint8_t find(std::uint8_t i) {
        while (parent[i] != i) i = parent[i] = parent[parent[i]];
        return i;
    }
    void unite(std::uint8_t a, std::uint8_t b) {
        a = find(a);
        b = find(b);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
};

/// next[e] = the edge where the segment starting at crossed edge e ends (0xff if e is uncrossed).
std::array<std::uint8_t, 12> segment_successors(std::uint8_t config, std::uint8_t joined_faces) {
    std::array<std::uint8_t, 12> next;
    next.fill(0xff);
    for (int f = 0; f < 6; ++f) {
        const auto& c = kFaceCorners[f];
        const bool ambiguous = (ambiguous_faces(config) >> f) & 1u;
        const bool joined = (joined_faces >> f) & 1u;
        for (int i = 0; i < 4; ++i) {
            if (!inside(config, c[i]) || inside(config, c[(i + 1) % 4])) continue;
            int end = -1;  // index j of the face edge (c[j], c[j+1]) that ends the segment
            if (ambiguous) {
                end = joined ? (i + 1) % 4 : (i + 3) % 4;
            } else {
                for (int j = 0; j < 4; ++j) {
                    if (!inside(config, c[j]) && inside(config, c[(j + 1) % 4])) end = j;
                }
            }
            assert(end >= 0);
            next[edge_between(c[i], c[(i + 1) % 4])] = edge_between(c[end], c[(end + 1) % 4]);
        }
    }
    return next;
}

std::array<std::uint8_t, 8> corner_patches(std::uint8_t config, std::uint8_t joined_faces,
                                           std::uint8_t& patch_count) {
    UnionFind sets;
    for (const auto& e : kEdgeCorners) {
        if (inside(config, e[0]) == inside(config, e[1])) sets.unite(e[0], e[1]);
    }
    for (int f = 0; f < 6; ++f) {
        if (!((ambiguous_faces(config) >> f) & 1u)) continue;
        const auto& c = kFaceCorners[f];
        // The joined diagonal is the inside one when the face joins inside corners.
        const bool joined = (joined_faces >> f) & 1u;
        const int first = (inside(config, c[0]) == joined) ? 0 : 1;
        sets.unite(c[first], c[first + 2]);
    }
    std::array<std::uint8_t, 8> patch;
    std::array<std::uint8_t, 8> number;
    number.fill(0xff);
    patch_count = 0;
    for (std::uint8_t i = 0; i < 8; ++i) {
        const std::uint8_t root = sets.find(i);
        if (number[root] == 0xff) number[root] = patch_count++;
        patch[i] = number[root];
    }
    return patch;
}

CellLoops build_loops(std::uint8_t config, std::uint8_t joined_faces) {
    CellLoops loops;
    loops.corner_patch = corner_patches(config, joined_faces, loops.patch_count);
    std::array<std::uint8_t, 12> next = segment_successors(config, joined_faces);
    std::uint8_t count = 0;
    for (std::uint8_t start = 0; start < 12; ++start) {
        if (next[start] == 0xff) continue;
        assert(loops.loop_count < kMaxLoops);
        const int l = loops.loop_count++;
        loops.loop_begin[l] = count;
        for (std::uint8_t e = start; next[e] != 0xff;) {
            loops.vertices[count++] = e;
            const std::uint8_t successor = next[e];
            next[e] = 0xff;
            e = successor;
        }
        loops.loop_begin[l + 1] = count;
        const auto& corners = kEdgeCorners[start];
        const bool lower_inside = inside(config, corners[0]);
        loops.loop_patches[l] = {loops.corner_patch[corners[lower_inside ? 0 : 1]],
                                 loops.corner_patch[corners[lower_inside ? 1 : 0]]};
    }
    return loops;
}

/// All tables, indexed by offset[config] + the joined faces compressed to the ambiguous ones.
struct Tables {
    std::array<std::uint32_t, 256> offset{};
    std::vector<CellLoops> loops;

    Tables() {
        for (int config = 0; config < 256; ++config) {
            offset[config] = static_cast<std::uint32_t>(loops.size());
            const std::uint8_t ambiguous = ambiguous_faces(static_cast<std::uint8_t>(config));
            const int outcomes = 1 << std::popcount(ambiguous);
            for (int k = 0; k < outcomes; ++k) {
                loops.push_back(build_loops(static_cast<std::uint8_t>(config),
                                            expand(static_cast<std::uint8_t>(k), ambiguous)));
            }
        }
    }

    /// Scatters the low bits of `compact` onto the set bits of `mask` (the inverse of compress).
    static std::uint8_t expand(std::uint8_t compact, std::uint8_t mask) {
        std::uint8_t result = 0;
        for (int bit = 0, k = 0; bit < 6; ++bit) {
            if ((mask >> bit) & 1u)
                result |= static_cast<std::uint8_t>(((compact >> k++) & 1u) << bit);
        }
        return result;
    }
    static std::uint8_t compress(std::uint8_t value, std::uint8_t mask) {
        std::uint8_t result = 0;
        for (int bit = 0, k = 0; bit < 6; ++bit) {
            if ((mask >> bit) & 1u)
                result |= static_cast<std::uint8_t>(((value >> bit) & 1u) << k++);
        }
        return result;
    }
};

const Tables& tables() {
    static const Tables instance;
    return instance;
}

}  // namespace

std::uint8_t edge_between(std::uint8_t corner_a, std::uint8_t corner_b) {
    const std::uint8_t lo = std::min(corner_a, corner_b);
    const std::uint8_t axis_bit = static_cast<std::uint8_t>(corner_a ^ corner_b);
    assert(std::popcount(axis_bit) == 1);
    const int axis = std::countr_zero(axis_bit);
    // Edges along an axis are numbered by the other two coordinates, the lower axis first.
    const int u = (axis == 0) ? (lo >> 1) & 1 : lo & 1;
    const int v = (axis == 2) ? (lo >> 1) & 1 : (lo >> 2) & 1;
    return static_cast<std::uint8_t>(4 * axis + u + 2 * v);
}

std::uint8_t ambiguous_faces(std::uint8_t config) {
    std::uint8_t result = 0;
    for (int f = 0; f < 6; ++f) {
        const auto& c = kFaceCorners[f];
        const bool s0 = inside(config, c[0]);
        if (s0 == inside(config, c[2]) && s0 != inside(config, c[1]) &&
            s0 != inside(config, c[3])) {
            result |= static_cast<std::uint8_t>(1u << f);
        }
    }
    return result;
}

const CellLoops& cell_loops(std::uint8_t config, std::uint8_t joined_faces) {
    const Tables& t = tables();
    const std::uint8_t ambiguous = ambiguous_faces(config);
    assert((joined_faces & ~ambiguous) == 0);
    return t.loops[t.offset[config] + Tables::compress(joined_faces, ambiguous)];
}

}  // namespace isomesh::mc33
