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

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

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

glm::dvec3 edge_midpoint(std::uint8_t e) {
    const auto corner = [](int c) { return glm::dvec3(c & 1, (c >> 1) & 1, (c >> 2) & 1); };
    return 0.5 * (corner(kEdgeCorners[e][0]) + corner(kEdgeCorners[e][1]));
}

/// Minimum-weight triangulation of a polygon (dynamic programming over sub-polygons, Klincsek
/// 1980) using no chord (diagonal lying in a face). Returns false when no such triangulation
/// exists.
bool triangulate_polygon(const std::uint8_t* v, int n,
                         std::vector<std::array<std::uint8_t, 3>>& out) {
    constexpr double kImpossible = 1e300;
    double cost[12][12];
    int apex[12][12];
    const auto diagonal = [&](int i, int j) {
        if (j == i + 1 || (i == 0 && j == n - 1)) return 0.0;  // a side of the polygon
        return may_join(v[i], v[j], Chords::kNone)
                   ? glm::distance(edge_midpoint(v[i]), edge_midpoint(v[j]))
                   : kImpossible;
    };
    for (int gap = 1; gap < n; ++gap) {
        for (int i = 0; i + gap < n; ++i) {
            const int j = i + gap;
            cost[i][j] = gap == 1 ? 0.0 : kImpossible;
            apex[i][j] = -1;
            for (int k = i + 1; k < j; ++k) {
                const double c = cost[i][k] + cost[k][j] + diagonal(i, k) + diagonal(k, j);
                if (c < cost[i][j]) {
                    cost[i][j] = c;
                    apex[i][j] = k;
                }
            }
        }
    }
    if (cost[0][n - 1] >= kImpossible) return false;
    const auto emit = [&](auto& self, int i, int j) -> void {
        if (j - i < 2) return;
        const int k = apex[i][j];
        out.push_back({v[i], v[k], v[j]});
        self(self, i, k);
        self(self, k, j);
    };
    emit(emit, 0, n - 1);
    return true;
}

void triangulate_disks(CellLoops& loops) {
    std::vector<std::array<std::uint8_t, 3>> triangles;
    for (int l = 0; l < loops.loop_count; ++l) {
        loops.disk_begin[l] = static_cast<std::uint8_t>(triangles.size());
        const std::uint8_t* v = loops.loop(l);
        const int n = loops.loop_size(l);
        if (n < 7 && triangulate_polygon(v, n, triangles)) continue;
        assert(loops.interior_vertex_edges == 0);  // one interior vertex per cell
        for (int i = 0; i < n; ++i) {
            triangles.push_back({v[i], v[(i + 1) % n], kInteriorVertex});
            loops.interior_vertex_edges |= static_cast<std::uint16_t>(1u << v[i]);
        }
    }
    loops.disk_begin[loops.loop_count] = static_cast<std::uint8_t>(triangles.size());
    assert(triangles.size() <= loops.triangles.size());
    std::copy(triangles.begin(), triangles.end(), loops.triangles.begin());
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
    triangulate_disks(loops);
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
    // Never destroyed: a worker thread may still be meshing while the process exits (a server
    // stopped by exit(), a fuzzer reaching its time limit), after static destructors have run.
    static const Tables* const instance = new Tables();
    return *instance;
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

std::uint8_t edge_faces(std::uint8_t edge) {
    const auto& c = kEdgeCorners[edge];
    std::uint8_t faces = 0;
    for (int axis = 0; axis < 3; ++axis) {
        const int bit = 1 << axis;
        if ((c[0] & bit) != (c[1] & bit)) continue;  // the edge runs along this axis
        faces |= static_cast<std::uint8_t>(1u << (2 * axis + ((c[0] & bit) ? 1 : 0)));
    }
    return faces;
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
