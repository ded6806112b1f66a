// Checks of the generated MC33 tables and of triangulate_cell over every sign configuration and
// face-test outcome, and the classification of the realised configurations into Chernyaev's cases.
#include <gtest/gtest.h>

#include <iostream>

#include <algorithm>
#include <array>
#include <bit>
#include <map>
#include <random>
#include <set>
#include <tuple>
#include <utility>

#include "polygonize/mc33.h"
#include "polygonize/mc33_tables.h"

namespace isomesh {
namespace {

using mc33::CellLoops;

bool inside(int config, int corner) {
    return (config >> corner) & 1;
}

/// The directed boundary segments a cell's surface must have on the faces: each loop's
/// consecutive vertices.
std::set<std::pair<int, int>> loop_segments(const CellLoops& loops) {
    std::set<std::pair<int, int>> segments;
    for (int l = 0; l < loops.loop_count; ++l) {
        const int n = loops.loop_size(l);
        for (int k = 0; k < n; ++k) segments.insert({loops.loop(l)[k], loops.loop(l)[(k + 1) % n]});
    }
    return segments;
}

/// Directed edges used by the triangles, and whether any is used twice in one direction.
std::map<std::pair<int, int>, int> directed_edges(const CellTriangulation& cell) {
    std::map<std::pair<int, int>, int> edges;
    for (int t = 0; t < cell.triangle_count; ++t) {
        for (int k = 0; k < 3; ++k) ++edges[{cell.triangles[t][k], cell.triangles[t][(k + 1) % 3]}];
    }
    return edges;
}

TEST(Mc33Tables, face_corners_are_counter_clockwise_from_inside) {
    for (int f = 0; f < 6; ++f) {
        const auto p = [&](int k) {
            const int c = mc33::kFaceCorners[f][k];
            return std::array<int, 3>{c & 1, (c >> 1) & 1, (c >> 2) & 1};
        };
        const int axis = f / 2;
        const int inward = (f % 2 == 0) ? 1 : -1;
        for (int k = 0; k < 4; ++k) EXPECT_EQ(p(k)[axis], f % 2) << "face " << f;
        const auto a = p(0), b = p(1), c = p(2);
        const std::array<int, 3> u{b[0] - a[0], b[1] - a[1], b[2] - a[2]};
        const std::array<int, 3> v{c[0] - b[0], c[1] - b[1], c[2] - b[2]};
        const std::array<int, 3> n{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                                   u[0] * v[1] - u[1] * v[0]};
        EXPECT_EQ(n[axis], inward) << "face " << f;
    }
}

TEST(Mc33Tables, edges_join_corners_along_their_axis) {
    for (int e = 0; e < 12; ++e) {
        const auto [a, b] = kEdgeCorners[e];
        EXPECT_EQ(std::popcount(static_cast<unsigned>(a ^ b)), 1);
        EXPECT_EQ(a ^ b, 1 << (e / 4)) << "edge " << e;
        EXPECT_LT(a, b);
        EXPECT_EQ(mc33::edge_between(a, b), e);
        EXPECT_EQ(
            std::popcount(static_cast<unsigned>(mc33::edge_faces(static_cast<std::uint8_t>(e)))),
            2);
    }
}

// Every configuration and every outcome of its face tests: the loops cover exactly the crossed
// edges, the patches form a tree with the loops (a sphere cut by k loops has k + 1 regions), and
// the disks are closed, consistently oriented, chord-free and bounded by their loop.
TEST(Mc33Tables, every_entry_has_closed_oriented_disks) {
    int entries = 0, expected_entries = 0;
    for (int config = 0; config < 256; ++config) {
        const std::uint8_t ambiguous = mc33::ambiguous_faces(static_cast<std::uint8_t>(config));
        expected_entries += 1 << std::popcount(ambiguous);
        for (int joined = 0; joined < 64; ++joined) {
            if ((joined & ~ambiguous) != 0) continue;
            ++entries;
            const CellLoops& loops = mc33::cell_loops(static_cast<std::uint8_t>(config),
                                                      static_cast<std::uint8_t>(joined));
            std::set<int> crossed, looped;
            for (int e = 0; e < 12; ++e) {
                if (inside(config, kEdgeCorners[e][0]) != inside(config, kEdgeCorners[e][1]))
                    crossed.insert(e);
            }
            for (int k = 0; k < loops.loop_begin[loops.loop_count]; ++k) {
                EXPECT_TRUE(looped.insert(loops.vertices[k]).second);
            }
            EXPECT_EQ(crossed, looped) << "config " << config;
            if (config != 0 && config != 255) {
                EXPECT_EQ(loops.patch_count, loops.loop_count + 1)
                    << "config " << config << " joined " << joined;
            }
            int interior_users = 0;
            for (int l = 0; l < loops.loop_count; ++l) {
                CellTriangulation disk;
                for (int t = loops.disk_begin[l]; t < loops.disk_begin[l + 1]; ++t) {
                    disk.triangles[disk.triangle_count++] = loops.triangles[t];
                }
                interior_users += disk.triangles[0][2] == kInteriorVertex ? 1 : 0;
                std::set<std::pair<int, int>> boundary;
                for (const auto& [edge, count] : directed_edges(disk)) {
                    EXPECT_EQ(count, 1) << "config " << config << " loop " << l;
                    const auto reverse = std::make_pair(edge.second, edge.first);
                    const bool interior = directed_edges(disk).count(reverse) > 0;
                    if (!interior) boundary.insert(edge);
                    if (interior && edge.first != kInteriorVertex &&
                        edge.second != kInteriorVertex) {
                        EXPECT_TRUE(mc33::may_join(static_cast<std::uint8_t>(edge.first),
                                                   static_cast<std::uint8_t>(edge.second),
                                                   mc33::Chords::kNone));
                    }
                }
                CellLoops single = loops;
                single.loop_count = 1;
                single.loop_begin = {loops.loop_begin[l], loops.loop_begin[l + 1]};
                EXPECT_EQ(boundary, loop_segments(single)) << "config " << config << " loop " << l;
            }
            EXPECT_LE(interior_users, 1);
        }
    }
    EXPECT_EQ(entries, expected_entries);
}

/// A symmetry of the cube (axis permutation and reversals), optionally with complementation.
struct Symmetry {
    std::array<int, 3> axis;  // new axis k takes old axis axis[k]
    int flips;                // bit k: new axis k is reversed
    bool complement;

    int corner(int c) const {
        int result = 0;
        for (int k = 0; k < 3; ++k) result |= (((c >> axis[k]) & 1) ^ ((flips >> k) & 1)) << k;
        return result;
    }
    int face(int f) const {
        const int k = static_cast<int>(std::find(axis.begin(), axis.end(), f / 2) - axis.begin());
        return 2 * k + ((f % 2) ^ ((flips >> k) & 1));
    }
    /// The image of (config, joined faces, tube): complementing turns "inside joined" into
    /// "outside joined", i.e. flips every ambiguous face's outcome.
    std::tuple<int, int, bool> apply(int config, int joined, bool tube) const {
        int image = 0, image_joined = 0;
        for (int c = 0; c < 8; ++c) image |= ((config >> c) & 1) << corner(c);
        for (int f = 0; f < 6; ++f) image_joined |= ((joined >> f) & 1) << face(f);
        if (complement) {
            image ^= 0xff;
            image_joined ^= mc33::ambiguous_faces(static_cast<std::uint8_t>(image));
        }
        return {image, image_joined, tube};
    }
};

/// The 24 rotations of the cube, with and without complementation (reflections are left out:
/// they would merge cases 11 and 14, which are mirror images).
std::vector<Symmetry> rotations_and_complement() {
    std::vector<Symmetry> group;
    std::array<int, 3> axis{0, 1, 2};
    do {
        const int inversions = (axis[0] > axis[1]) + (axis[0] > axis[2]) + (axis[1] > axis[2]);
        for (int flips = 0; flips < 8; ++flips) {
            if ((inversions + std::popcount(static_cast<unsigned>(flips))) % 2 != 0) continue;
            for (const bool complement : {false, true}) group.push_back({axis, flips, complement});
        }
    } while (std::next_permutation(axis.begin(), axis.end()));
    return group;
}

// Random trilinear cells (uniform values in [-1, 1], and perturbed checkerboards to reach the
// rare subcases of case 13): the triangulation is bounded exactly by the loops of its table entry,
// every interior edge has two triangles in opposite directions, a tube removes two disks, the
// interior test joins at most one pair of patches, and the configurations realised fall into
// Chernyaev's 33 cases: 15 sign classes (cases 0 to 14) and 33 classes of (signs, face outcomes,
// tube) under the cube's rotations and complementation.
TEST(Mc33Tables, random_cells_are_closed_and_fall_into_33_cases) {
    std::mt19937_64 random(12345);
    std::uniform_real_distribution<double> uniform(-1.0, 1.0);
    std::set<std::tuple<int, int, bool>> realised;
    for (int sample = 0; sample < 150000; ++sample) {
        std::array<double, 8> f;
        // Every other sample is a small perturbation of a checkerboard, around a body saddle.
        const double scale = sample % 2 == 0 ? 1.0 : 0.6;
        for (int c = 0; c < 8; ++c) {
            const double checker = std::popcount(static_cast<unsigned>(c)) % 2 == 0 ? 1.0 : -1.0;
            f[c] = uniform(random) * scale + (sample % 2 == 0 ? 0.0 : 0.5 * checker);
        }
        const CellDecision decision = decide_cell(f);
        ASSERT_LE(decision.interior_joins, 1);
        const CellTriangulation cell = triangulate_cell(f);
        const CellLoops& loops = mc33::cell_loops(decision.config, decision.joined_faces);
        const auto edges = directed_edges(cell);
        std::set<std::pair<int, int>> boundary;
        for (const auto& [edge, count] : edges) {
            ASSERT_EQ(count, 1) << "config " << int(decision.config);
            if (!edges.count({edge.second, edge.first})) boundary.insert(edge);
        }
        ASSERT_EQ(boundary, loop_segments(loops)) << "config " << int(decision.config);
        const bool tube = decision.tube[0] >= 0;
        std::set<int> vertices;
        for (int t = 0; t < cell.triangle_count; ++t)
            vertices.insert(cell.triangles[t].begin(), cell.triangles[t].end());
        std::set<std::pair<int, int>> undirected;
        for (const auto& [edge, count] : edges)
            undirected.insert(std::minmax(edge.first, edge.second));
        const long chi = static_cast<long>(vertices.size()) - static_cast<long>(undirected.size()) +
                         cell.triangle_count;
        ASSERT_EQ(chi, loops.loop_count - (tube ? 2 : 0)) << "config " << int(decision.config);
        realised.insert({decision.config, decision.joined_faces, tube});
    }
    const std::vector<Symmetry> group = rotations_and_complement();
    EXPECT_EQ(group.size(), 48u);
    std::set<std::tuple<int, int, bool>> classes;
    std::set<int> sign_classes;
    for (const auto& [config, joined, tube] : realised) {
        std::tuple<int, int, bool> canonical{256, 0, false};
        int canonical_config = 256;
        for (const Symmetry& s : group) {
            canonical = std::min(canonical, s.apply(config, joined, tube));
            canonical_config = std::min(canonical_config, std::get<0>(s.apply(config, 0, false)));
        }
        if (classes.insert(canonical).second) {
            std::cout << "class: config " << std::get<0>(canonical) << " joined faces "
                      << std::get<1>(canonical) << (std::get<2>(canonical) ? " tube" : "") << "\n";
        }
        sign_classes.insert(canonical_config);
    }
    EXPECT_EQ(sign_classes.size(), 15u);
    EXPECT_EQ(classes.size(), 33u);
}

}  // namespace
}  // namespace isomesh
