// Marching Cubes 33 cell triangulation (see mc33.h for the papers and conventions, and
// mc33_tables.h for how the contour loops are generated).
//
// Interior test. Let F be the trilinear interpolant. F is harmonic, so every connected region of
// {F < 0} (or {F > 0}) in the cell touches the cell's surface, and the surface inside the cell is
// a disk per contour loop unless two same-sign patches of the cell's surface are connected through
// the interior (a tube). Following Chernyaev, we look for such connections in the slices z = t:
// in a slice F is bilinear (harmonic again), so each region of a slice holds a point of one of
// the four vertical edges. Two vertical edges that share a side face connect only through that
// face (already known from the face tests), so the interior adds exactly the connections between
// the two diagonal pairs of vertical edges: edges (a, d) with the other two (b, c) connect in
// slice t when a(t) and d(t) have the same sign and a(t) d(t) > b(t) c(t) (the asymptotic decider
// of the slice, Nielson & Hamann 1991). q(t) = a d - b c is quadratic in t, so its maximum over
// the heights where a and d share the sign is found in closed form. Lewiner et al. (2003) apply
// the same slice test to a fixed pair of corners per case; Custodio et al. (2013) list the cases
// where that choice misses a connection. Testing both diagonals, for both signs, in every
// configuration leaves no case out. At t = 0 and t = 1 the slice test is evaluated with the exact
// products of the face test, so it can only agree with it.
#include "polygonize/mc33.h"

#include <algorithm>
#include <bit>
#include <cassert>
#include <limits>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "polygonize/mc33_tables.h"

namespace isomesh {
namespace {

bool is_inside(double value) {
    return value < 0.0;
}

double lerp(double v0, double v1, double t) {
    return (1.0 - t) * v0 + t * v1;
}

/// The open range of heights t in (0, 1) where the vertical edge (v0 at t = 0, v1 at t = 1) is
/// strictly on the `inside` side (F < 0) or strictly outside (F > 0). lo >= hi when empty.
struct Range {
    double lo = 1.0;
    double hi = 0.0;
};
Range signed_range(double v0, double v1, bool inside) {
    const double g0 = inside ? -v0 : v0;
    const double g1 = inside ? -v1 : v1;
    if (g0 > 0.0 && g1 > 0.0) return {0.0, 1.0};
    if (g0 > 0.0) return {0.0, g0 / (g0 - g1)};
    if (g1 > 0.0) return {g0 / (g0 - g1), 1.0};
    return {};
}

/// Whether the vertical edges over corners a and d (bottom corner indices, b and c the other
/// two) are connected through a slice of the cell on the given side.
bool slices_join(const std::array<double, 8>& f, int a, int d, int b, int c, bool inside) {
    const Range ra = signed_range(f[a], f[a + 4], inside);
    const Range rd = signed_range(f[d], f[d + 4], inside);
    const double lo = std::max(ra.lo, rd.lo);
    const double hi = std::min(ra.hi, rd.hi);
    if (!(lo < hi)) return false;
    const auto q = [&](double t) {
        return lerp(f[a], f[a + 4], t) * lerp(f[d], f[d + 4], t) -
               lerp(f[b], f[b + 4], t) * lerp(f[c], f[c + 4], t);
    };
    if (q(lo) > 0.0 || q(hi) > 0.0) return true;
    const double da = f[a + 4] - f[a], dd = f[d + 4] - f[d];
    const double db = f[b + 4] - f[b], dc = f[c + 4] - f[c];
    const double quadratic = da * dd - db * dc;
    if (!(quadratic < 0.0)) return false;  // q is convex or linear: its maximum is at an end
    const double linear = f[a] * dd + f[d] * da - f[b] * dc - f[c] * db;
    const double t = -linear / (2.0 * quadratic);
    return lo < t && t < hi && q(t) > 0.0;
}

struct PatchSets {
    std::array<std::uint8_t, 8> parent{0, 1, 2, 3, 4, 5, 6, 7};
    std::uint8_t find(std::uint8_t i) const {
        while (parent[i] != i) i = parent[i];
        return i;
    }
};

/// The two loops bounding the tube that joins patches p1 and p2 (same sign) through the cell:
/// each bounds one of them, and both bound a common patch of the other sign.
std::array<std::int8_t, 2> tube_loops(const mc33::CellLoops& loops, std::uint8_t p1,
                                      std::uint8_t p2, bool inside) {
    const int own = inside ? 0 : 1;
    for (int l1 = 0; l1 < loops.loop_count; ++l1) {
        if (loops.loop_patches[l1][own] != p1) continue;
        for (int l2 = 0; l2 < loops.loop_count; ++l2) {
            if (loops.loop_patches[l2][own] == p2 &&
                loops.loop_patches[l2][1 - own] == loops.loop_patches[l1][1 - own]) {
                return {static_cast<std::int8_t>(std::min(l1, l2)),
                        static_cast<std::int8_t>(std::max(l1, l2))};
            }
        }
    }
    return {-1, -1};
}

glm::dvec3 corner_position(int corner) {
    return {static_cast<double>(corner & 1), static_cast<double>((corner >> 1) & 1),
            static_cast<double>((corner >> 2) & 1)};
}

/// The crossing of edge e by linear interpolation, in cell coordinates [0, 1]^3.
glm::dvec3 crossing(const std::array<double, 8>& f, int e) {
    const int u = kEdgeCorners[e][0], v = kEdgeCorners[e][1];
    const double denominator = f[u] - f[v];
    const double t = denominator != 0.0 ? std::clamp(f[u] / denominator, 0.0, 1.0) : 0.5;
    return corner_position(u) + t * (corner_position(v) - corner_position(u));
}

class TriangleWriter {
  public:
    explicit TriangleWriter(CellTriangulation& out) : out_(out) {}
    void add(std::uint8_t a, std::uint8_t b, std::uint8_t c) {
        assert(out_.triangle_count < out_.triangles.size());
        out_.triangles[out_.triangle_count++] = {a, b, c};
    }

  private:
    CellTriangulation& out_;
};

/// A tube between loops A and B is a strip: a cyclic sequence of triangles, each advancing one
/// step along A (forwards) or along B (backwards: the loops' orientations as the tube's two
/// boundaries), joined by rungs (a_i, b_j). A rung may not repeat (that would pinch the tube) and
/// should not be a chord (mc33::Chords). When no strip avoids chords, a contiguous block of the
/// strip runs through the interior vertex c instead: rungs a_i - c - b_j, entered by the triangle
/// (b_j, a_i, c) and left by (c, a_i, b_j). When that fails too, chords of the faces the cell owns
/// are allowed, and last (the tube of 7.4.2 or its complement hugging the three faces of a corner
/// that the cell does not own) any chord: the neighbour across the face then draws the same chord
/// only if it is itself a tube cell using a chord of that face, which the suites never produce.
struct Strip {
    int start_a = 0;  ///< the first rung is (a_start_a, b_start_b)
    int start_b = 0;
    unsigned moves = 0;    ///< bit k: step k advances along A (else along B)
    int block_begin = -1;  ///< steps [block_begin, block_end] run through c; -1: no block
    int block_end = -1;
};

class TubeStrips {
  public:
    TubeStrips(const std::uint8_t* a, int m, const std::uint8_t* b, int n,
               const std::array<double, 8>& f)
        : a_(a), b_(b), m_(m), n_(n) {
        glm::dvec3 sum(0.0);
        for (int i = 0; i < m; ++i) sum += pa_[i] = crossing(f, a[i]);
        for (int j = 0; j < n; ++j) sum += pb_[j] = crossing(f, b[j]);
        centre_ = sum / static_cast<double>(m + n);
    }

    /// The strip of least total rung length, without c if any exists.
    Strip best() const {
        Strip best_strip;
        double best_cost = kInvalid;
        // From the most to the least preferred (see Strip).
        using mc33::Chords;
        constexpr std::pair<bool, Chords> kTiers[] = {{false, Chords::kNone},
                                                      {true, Chords::kNone},
                                                      {false, Chords::kOwned},
                                                      {true, Chords::kOwned},
                                                      {false, Chords::kAny}};
        for (const auto& [with_centre, chords] : kTiers) {
            for (int ij = 0; ij < m_ * n_; ++ij) {
                for (unsigned moves = 0; moves < (1u << (m_ + n_)); ++moves) {
                    if (std::popcount(moves) != m_) continue;
                    const int steps = m_ + n_;
                    for (int begin = with_centre ? 0 : -1; begin < (with_centre ? steps : 0);
                         ++begin) {
                        for (int end = with_centre ? begin : -1; end < (with_centre ? steps : 0);
                             ++end) {
                            const Strip strip{ij / n_, ij % n_, moves, begin, end};
                            const double c = cost(strip, chords);
                            if (c < best_cost) {
                                best_cost = c;
                                best_strip = strip;
                            }
                        }
                    }
                }
            }
            if (best_cost < kInvalid) return best_strip;
        }
        assert(false && "no tube strip");
        return best_strip;
    }

    void emit(const Strip& strip, CellTriangulation& out) const {
        TriangleWriter writer(out);
        int i = strip.start_a, j = strip.start_b;
        for (int step = 0; step < m_ + n_; ++step) {
            const bool in_block = strip.block_begin <= step && step <= strip.block_end;
            if (step == strip.block_begin) writer.add(b_[j], a_[i], kInteriorVertex);
            const std::uint8_t other_b = in_block ? kInteriorVertex : b_[j];
            const std::uint8_t other_a = in_block ? kInteriorVertex : a_[i];
            if ((strip.moves >> step) & 1u) {
                const int i1 = (i + 1) % m_;
                writer.add(a_[i], a_[i1], other_b);
                i = i1;
            } else {
                const int j1 = (j + n_ - 1) % n_;
                writer.add(b_[j1], b_[j], other_a);
                j = j1;
            }
            if (step == strip.block_end) writer.add(kInteriorVertex, a_[i], b_[j]);
        }
    }

    /// Bit e set for the edges of both loops (c sits at the mean of their crossings).
    std::uint16_t edges() const {
        std::uint16_t mask = 0;
        for (int i = 0; i < m_; ++i) mask |= static_cast<std::uint16_t>(1u << a_[i]);
        for (int j = 0; j < n_; ++j) mask |= static_cast<std::uint16_t>(1u << b_[j]);
        return mask;
    }

  private:
    static constexpr double kInvalid = std::numeric_limits<double>::infinity();

    /// Summed rung lengths (c estimated at the loops' centre), or kInvalid.
    double cost(const Strip& strip, mc33::Chords chords) const {
        const auto may_join = [chords](std::uint8_t a, std::uint8_t b) {
            return mc33::may_join(a, b, chords);
        };
        const int steps = m_ + n_;
        if (strip.block_begin >= 0) {
            int along_a = 0;
            for (int step = strip.block_begin; step <= strip.block_end; ++step) {
                along_a += (strip.moves >> step) & 1u;
            }
            const int along_b = strip.block_end - strip.block_begin + 1 - along_a;
            if (along_a >= m_ || along_b >= n_) return kInvalid;  // c would repeat a vertex
        }
        int i = strip.start_a, j = strip.start_b;
        if (!may_join(a_[i], b_[j])) return kInvalid;
        std::array<std::uint16_t, 12> seen{};  // seen[i] bit j: rung (a_i, b_j) used
        seen[i] = static_cast<std::uint16_t>(1u << j);
        double total = glm::distance(pa_[i], pb_[j]);
        for (int step = 0; step + 1 < steps; ++step) {  // the last step closes on the first rung
            if ((strip.moves >> step) & 1u) {
                i = (i + 1) % m_;
            } else {
                j = (j + n_ - 1) % n_;
            }
            if (strip.block_begin <= step && step < strip.block_end) {
                total += glm::distance(pa_[i], centre_) + glm::distance(pb_[j], centre_);
                continue;
            }
            if (!may_join(a_[i], b_[j]) || ((seen[i] >> j) & 1u)) return kInvalid;
            seen[i] |= static_cast<std::uint16_t>(1u << j);
            total += glm::distance(pa_[i], pb_[j]);
        }
        return total;
    }

    const std::uint8_t* a_;
    const std::uint8_t* b_;
    int m_, n_;
    std::array<glm::dvec3, 12> pa_, pb_;
    glm::dvec3 centre_;
};

/// Triangulates the tube between loops A and B (see Strip).
void triangulate_tube(const std::uint8_t* a, int m, const std::uint8_t* b, int n,
                      const std::array<double, 8>& f, CellTriangulation& out) {
    const TubeStrips strips(a, m, b, n, f);
    const Strip strip = strips.best();
    strips.emit(strip, out);
    if (strip.block_begin >= 0) out.interior_vertex_edges = strips.edges();
}

}  // namespace

bool CellTriangulation::uses_interior_vertex() const {
    return interior_vertex_edges != 0;
}

std::uint8_t corner_configuration(const std::array<double, 8>& corner_values) {
    std::uint8_t config = 0;
    for (int i = 0; i < 8; ++i) {
        if (is_inside(corner_values[i])) config |= static_cast<std::uint8_t>(1u << i);
    }
    return config;
}

bool face_joins_inside(double a, double b, double c, double d) {
    // The saddle value (ac - bd) / (a + c - b - d) of the bilinear face is negative, joining the
    // inside corners, exactly when the inside diagonal's product exceeds the outside one's.
    const double ac = a * c, bd = b * d;
    return is_inside(a) ? ac > bd : bd > ac;
}

CellDecision decide_cell(const std::array<double, 8>& f) {
    CellDecision decision;
    decision.config = corner_configuration(f);
    const std::uint8_t ambiguous = mc33::ambiguous_faces(decision.config);
    for (int face = 0; face < 6; ++face) {
        if (!((ambiguous >> face) & 1u)) continue;
        const auto& c = mc33::kFaceCorners[face];
        if (face_joins_inside(f[c[0]], f[c[1]], f[c[2]], f[c[3]])) {
            decision.joined_faces |= static_cast<std::uint8_t>(1u << face);
        }
    }
    const mc33::CellLoops& loops = mc33::cell_loops(decision.config, decision.joined_faces);
    if (loops.loop_count < 2) return decision;  // one loop bounds a disk

    PatchSets patches;
    constexpr int kDiagonals[2][4] = {{0, 3, 1, 2}, {1, 2, 0, 3}};
    for (const auto& [a, d, b, c] : kDiagonals) {
        for (const bool inside : {true, false}) {
            if (!slices_join(f, a, d, b, c, inside)) continue;
            // The bottom or top corner of each edge on that side (one exists: the range is not
            // empty); both corners of an edge on one side share a patch.
            const int ca = is_inside(f[a]) == inside ? a : a + 4;
            const int cd = is_inside(f[d]) == inside ? d : d + 4;
            const std::uint8_t p1 = patches.find(loops.corner_patch[ca]);
            const std::uint8_t p2 = patches.find(loops.corner_patch[cd]);
            if (p1 == p2) continue;
            if (decision.interior_joins++ == 0) decision.tube = tube_loops(loops, p1, p2, inside);
            patches.parent[std::max(p1, p2)] = std::min(p1, p2);
        }
    }
    return decision;
}

CellTriangulation triangulate_cell(const std::array<double, 8>& corner_values) {
    CellTriangulation out;
    const CellDecision decision = decide_cell(corner_values);
    if (decision.config == 0 || decision.config == 0xff) return out;
    const mc33::CellLoops& loops = mc33::cell_loops(decision.config, decision.joined_faces);
    for (int l = 0; l < loops.loop_count; ++l) {
        if (l == decision.tube[0] || l == decision.tube[1]) continue;
        for (int t = loops.disk_begin[l]; t < loops.disk_begin[l + 1]; ++t) {
            out.triangles[out.triangle_count++] = loops.triangles[t];
        }
        if (loops.triangles[loops.disk_begin[l]][2] == kInteriorVertex) {
            out.interior_vertex_edges = loops.interior_vertex_edges;
        }
    }
    if (decision.tube[0] >= 0) {
        const int la = decision.tube[0], lb = decision.tube[1];
        triangulate_tube(&loops.vertices[loops.loop_begin[la]], loops.loop_size(la),
                         &loops.vertices[loops.loop_begin[lb]], loops.loop_size(lb), corner_values,
                         out);
    }
    return out;
}

}  // namespace isomesh
