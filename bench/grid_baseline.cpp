// The uniform-grid baseline (see grid_baseline.h).
#include "grid_baseline.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include <glm/geometric.hpp>

#include "bench_clock.h"
#include "eval/batch_kernels.h"  // ISOMESH_VECTOR_CLONES
#include "polygonize/mc33.h"
#include "polygonize/mc33_tables.h"

namespace isomesh::bench {
namespace {

constexpr std::uint32_t kNone = 0xffffffffu;

// Raw restrict pointers and AVX2 clones, so that GCC vectorizes the loops.
ISOMESH_VECTOR_CLONES void classify(const double* __restrict f, std::uint8_t* __restrict inside,
                                    std::size_t n) {
    for (std::size_t q = 0; q < n; ++q) inside[q] = f[q] < 0.0;
}

/// The Marching Cubes configurations (mc33.h: bit c for corner c inside) of a row of cells, from
/// the inside flags of its four grid rows: a0 (y, z), a1 (y + 1, z), b0 (y, z + 1), b1 (y + 1,
/// z + 1).
ISOMESH_VECTOR_CLONES void configurations(const std::uint8_t* __restrict a0,
                                          const std::uint8_t* __restrict a1,
                                          const std::uint8_t* __restrict b0,
                                          const std::uint8_t* __restrict b1,
                                          std::uint8_t* __restrict out, int cells) {
    for (int i = 0; i < cells; ++i) {
        out[i] =
            static_cast<std::uint8_t>(a0[i] | a0[i + 1] << 1 | a1[i] << 2 | a1[i + 1] << 3 |
                                      b0[i] << 4 | b0[i + 1] << 5 | b1[i] << 6 | b1[i + 1] << 7);
    }
}

/// The triangles of the configurations whose triangulation does not depend on the values.
struct FixedCases {
    std::array<bool, 256> fixed{};
    std::array<std::uint8_t, 256> count{};
    std::array<std::array<std::array<std::uint8_t, 3>, 12>, 256> triangles{};

    FixedCases() {
        for (int config = 1; config < 255; ++config) {
            const auto c = static_cast<std::uint8_t>(config);
            if (mc33::ambiguous_faces(c) != 0) continue;
            const mc33::CellLoops& loops = mc33::cell_loops(c, 0);
            if (loops.loop_count != 1 || loops.interior_vertex_edges != 0) continue;
            fixed[config] = true;
            count[config] = loops.disk_begin[1];
            for (int t = 0; t < count[config]; ++t) triangles[config][t] = loops.triangles[t];
        }
    }
};

const FixedCases& fixed_cases() {
    static const FixedCases cases;
    return cases;
}

/// The sign changes of one grid row (points 0..n along x): points [0, lo] have the sign of point
/// 0 (`left`), points [hi, n] that of point n (`right`). No change: lo = n, hi = 0.
struct RowSpan {
    int lo = 0;
    int hi = 0;
    std::uint8_t left = 0;
    std::uint8_t right = 0;
};

struct Plane {
    std::vector<double> f;             // f[i + (n + 1) j]
    std::vector<std::uint8_t> inside;  // f < 0 (NaN counts as outside)
    std::vector<RowSpan> rows;         // per j
};

/// Vertex ids of the crossed edges lying in one grid plane.
struct PlaneEdges {
    std::vector<std::uint32_t> x;  // x-edge (i, i + 1) of row j: x[i + n j]
    std::vector<std::uint32_t> y;  // y-edge (j, j + 1) at point i: y[i + (n + 1) j]
};

class GridMesher {
  public:
    GridMesher(NativeBatch f, const Box& box, int n, GridTimes* times)
        : f_(f),
          n_(n),
          stride_(n + 1),
          points_(std::size_t(n + 1) * std::size_t(n + 1)),
          times_(times) {
        for (int axis = 0; axis < 3; ++axis) {
            coordinates_[axis].resize(stride_);
            for (int i = 0; i <= n; ++i) {
                coordinates_[axis][i] = box.lo[axis] + box.size()[axis] * (double(i) / double(n));
            }
            step_[axis] = box.size()[axis] / double(n);
        }
        xs_.resize(points_);
        ys_.resize(points_);
        zs_.resize(stride_);
        for (int j = 0; j <= n; ++j) {
            for (int i = 0; i <= n; ++i) {
                xs_[index(i, j)] = coordinates_[0][i];
                ys_[index(i, j)] = coordinates_[1][j];
            }
        }
        for (Plane& p : planes_) {
            p.f.resize(points_);
            p.inside.resize(points_);
            p.rows.resize(stride_);
        }
        for (PlaneEdges& e : edges_) {
            e.x.assign(std::size_t(n) * stride_, kNone);
            e.y.assign(std::size_t(n) * stride_, kNone);
        }
        z_edges_.assign(points_, kNone);
        configs_.resize(stride_);
        // More than most surfaces need (a closed surface across the box has about 6 n^2
        // triangles): address space only, the pages are touched as the mesh grows into them, and
        // no reallocation copies the mesh.
        mesh_.triangles.reserve(8 * points_);
        mesh_.positions.reserve(4 * points_);
        mesh_.normals.reserve(4 * points_);
    }

    Mesh run() {
        sample(0);
        sample(1);
        if (n_ >= 2) sample(2);
        plane_edges(0, edges_[0]);
        for (int k = 0; k < n_; ++k) {  // planes k - 1 .. k + 2 are sampled
            plane_edges(k + 1, edges_[(k + 1) & 1]);
            z_edges(k);
            slab(k);
            if (k + 3 <= n_) sample(k + 3);  // into plane k - 1's slot
        }
        return std::move(mesh_);
    }

  private:
    std::size_t index(int i, int j) const { return std::size_t(i) + std::size_t(stride_) * j; }
    Plane& plane(int k) { return planes_[k & 3]; }

    void sample(int k) {
        const double start = times_ ? cpu_seconds() : 0.0;
        Plane& p = plane(k);
        // Row by row: the x and y coordinates are the plane's, made once, and z fills one row.
        std::fill(zs_.begin(), zs_.end(), coordinates_[2][k]);
        for (int j = 0; j <= n_; ++j)
            f_(&xs_[index(0, j)], &ys_[index(0, j)], zs_.data(), &p.f[index(0, j)], stride_);
        if (times_) times_->sampling += cpu_seconds() - start;
        classify(p.f.data(), p.inside.data(), points_);
        for (int j = 0; j <= n_; ++j) p.rows[j] = row_span(&p.inside[index(0, j)]);
    }

    /// The bytes in[i] ^ in[i + 1] for i in [i, i + 8), as one word.
    static std::uint64_t changes(const std::uint8_t* in, int i) {
        std::uint64_t a = 0, b = 0;
        std::memcpy(&a, in + i, 8);
        std::memcpy(&b, in + i + 1, 8);
        return a ^ b;
    }

    /// First and last sign change of a row, 8 points at a time (in[0..n]).
    RowSpan row_span(const std::uint8_t* in) const {
        RowSpan span{n_, 0, in[0], in[n_]};
        int i = 0;
        for (; i + 8 <= n_; i += 8) {
            if (const std::uint64_t d = changes(in, i)) {
                i += std::countr_zero(d) / 8;
                break;
            }
        }
        while (i < n_ && in[i] == in[i + 1]) ++i;
        if (i == n_) return span;
        span.lo = i;
        int last = n_ - 1;  // the last edge that may change, scanned down in words
        for (; last - 7 > i; last -= 8) {
            if (const std::uint64_t d = changes(in, last - 7)) {
                last -= std::countl_zero(d) / 8;
                break;
            }
        }
        while (in[last] == in[last + 1]) --last;
        span.hi = last + 1;
        return span;
    }

    /// Inclusive range of points where two rows may differ in sign (empty when lo > hi).
    std::pair<int, int> point_range(const RowSpan& a, const RowSpan& b) const {
        return {a.left != b.left ? 0 : std::min(a.lo, b.lo),
                a.right != b.right ? n_ : std::max(a.hi, b.hi)};
    }

    /// Central differences of the samples (one-sided on the box's faces).
    glm::dvec3 gradient(int i, int j, int k) {
        const std::size_t q = index(i, j);
        const std::vector<double>& f = plane(k).f;
        const auto difference = [&](double below, double above, int lo, int hi, int axis) {
            return (above - below) / (double(hi - lo) * step_[axis]);
        };
        const int i0 = std::max(i - 1, 0), i1 = std::min(i + 1, n_);
        const int j0 = std::max(j - 1, 0), j1 = std::min(j + 1, n_);
        const int k0 = std::max(k - 1, 0), k1 = std::min(k + 1, n_);
        return {difference(f[index(i0, j)], f[index(i1, j)], i0, i1, 0),
                difference(f[index(i, j0)], f[index(i, j1)], j0, j1, 1),
                difference(plane(k0).f[q], plane(k1).f[q], k0, k1, 2)};
    }

    /// The vertex where the edge from grid point a to its neighbour b (one step along `axis`)
    /// crosses 0, or kNone when either value is not finite.
    std::uint32_t edge_vertex(glm::ivec3 a, int axis) {
        glm::ivec3 b = a;
        ++b[axis];
        const double fa = plane(a.z).f[index(a.x, a.y)];
        const double fb = plane(b.z).f[index(b.x, b.y)];
        if (!std::isfinite(fa) || !std::isfinite(fb)) return kNone;
        const double t = fa / (fa - fb);
        glm::dvec3 p{coordinates_[0][a.x], coordinates_[1][a.y], coordinates_[2][a.z]};
        p[axis] += t * step_[axis];
        const glm::dvec3 g = (1.0 - t) * gradient(a.x, a.y, a.z) + t * gradient(b.x, b.y, b.z);
        const double length = glm::length(g);
        mesh_.positions.push_back(p);
        mesh_.normals.push_back(length > 0.0 ? g / length : glm::dvec3(0.0));
        return static_cast<std::uint32_t>(mesh_.positions.size() - 1);
    }

    void plane_edges(int k, PlaneEdges& e) {
        const Plane& p = plane(k);
        for (int j = 0; j <= n_; ++j) {
            const std::uint8_t* in = &p.inside[index(0, j)];
            const RowSpan& r = p.rows[j];
            for (int i = r.lo; i < r.hi; ++i) {
                if (in[i] != in[i + 1]) e.x[i + std::size_t(n_) * j] = edge_vertex({i, j, k}, 0);
            }
        }
        for (int j = 0; j < n_; ++j) {
            const std::uint8_t* in0 = &p.inside[index(0, j)];
            const std::uint8_t* in1 = in0 + stride_;
            const auto [lo, hi] = point_range(p.rows[j], p.rows[j + 1]);
            for (int i = lo; i <= hi; ++i) {
                if (in0[i] != in1[i]) e.y[index(i, j)] = edge_vertex({i, j, k}, 1);
            }
        }
    }

    void z_edges(int k) {
        const Plane& p0 = plane(k);
        const Plane& p1 = plane(k + 1);
        for (int j = 0; j <= n_; ++j) {
            const std::uint8_t* in0 = &p0.inside[index(0, j)];
            const std::uint8_t* in1 = &p1.inside[index(0, j)];
            const auto [lo, hi] = point_range(p0.rows[j], p1.rows[j]);
            for (int i = lo; i <= hi; ++i) {
                if (in0[i] != in1[i]) z_edges_[index(i, j)] = edge_vertex({i, j, k}, 2);
            }
        }
    }

    void slab(int k) {
        const Plane& p0 = plane(k);
        const Plane& p1 = plane(k + 1);
        for (int j = 0; j < n_; ++j) {
            const RowSpan* rows[4] = {&p0.rows[j], &p0.rows[j + 1], &p1.rows[j], &p1.rows[j + 1]};
            bool lefts_differ = false, rights_differ = false;
            int lo = n_, hi = 0;
            for (const RowSpan* r : rows) {
                lefts_differ |= r->left != rows[0]->left;
                rights_differ |= r->right != rows[0]->right;
                lo = std::min(lo, r->lo);
                hi = std::max(hi, r->hi);
            }
            if (lefts_differ) lo = 0;
            if (rights_differ) hi = n_;
            if (lo >= hi) continue;
            const std::uint8_t* a0 = &p0.inside[index(0, j)];
            const std::uint8_t* b0 = &p1.inside[index(0, j)];
            configurations(a0 + lo, a0 + stride_ + lo, b0 + lo, b0 + stride_ + lo, configs_.data(),
                           hi - lo);
            for (int i = lo; i < hi; ++i) {
                const unsigned config = configs_[i - lo];
                if (config != 0 && config != 255) cell(i, j, k, config);
            }
        }
    }

    void cell(int i, int j, int k, unsigned config) {
        const PlaneEdges& e0 = edges_[k & 1];
        const PlaneEdges& e1 = edges_[(k + 1) & 1];
        const std::size_t xj = i + std::size_t(n_) * j, xj1 = xj + n_;
        const std::size_t q = index(i, j), q1 = q + stride_;
        const std::array<std::uint32_t, 13> ids{
            e0.x[xj],     e0.x[xj1],        e1.x[xj],    e1.x[xj1],   e0.y[q],
            e0.y[q + 1],  e1.y[q],          e1.y[q + 1], z_edges_[q], z_edges_[q + 1],
            z_edges_[q1], z_edges_[q1 + 1], kNone};
        const FixedCases& cases = fixed_cases();
        if (cases.fixed[config]) {
            emit(ids, cases.triangles[config].data(), cases.count[config]);
            return;
        }
        std::array<double, 8> values;
        for (int c = 0; c < 8; ++c) {
            values[c] = plane(k + (c >> 2)).f[index(i + (c & 1), j + ((c >> 1) & 1))];
            if (!std::isfinite(values[c])) return;
        }
        const CellTriangulation t = triangulate_cell(values);
        std::array<std::uint32_t, 13> with_centre = ids;
        if (t.uses_interior_vertex()) with_centre[kInteriorVertex] = centre(ids, t);
        emit(with_centre, t.triangles.data(), t.triangle_count);
    }

    /// The interior vertex of an MC33 subcase: the mean of its loop's crossings (mc33.h).
    std::uint32_t centre(const std::array<std::uint32_t, 13>& ids, const CellTriangulation& t) {
        glm::dvec3 p(0.0), normal(0.0);
        int count = 0;
        for (int e = 0; e < 12; ++e) {
            if (!((t.interior_vertex_edges >> e) & 1u) || ids[e] == kNone) continue;
            p += mesh_.positions[ids[e]];
            normal += mesh_.normals[ids[e]];
            ++count;
        }
        if (count == 0) return kNone;
        const double length = glm::length(normal);
        mesh_.positions.push_back(p / double(count));
        mesh_.normals.push_back(length > 0.0 ? normal / length : glm::dvec3(0.0));
        return static_cast<std::uint32_t>(mesh_.positions.size() - 1);
    }

    void emit(const std::array<std::uint32_t, 13>& ids, const std::array<std::uint8_t, 3>* tris,
              int count) {
        for (int t = 0; t < count; ++t) {
            const std::array<std::uint32_t, 3> tri{ids[tris[t][0]], ids[tris[t][1]],
                                                   ids[tris[t][2]]};
            if (tri[0] == kNone || tri[1] == kNone || tri[2] == kNone) continue;  // a NaN corner
            mesh_.triangles.push_back(tri);
        }
    }

    NativeBatch f_;
    int n_;
    int stride_;
    std::size_t points_;
    GridTimes* times_;
    std::array<std::vector<double>, 3> coordinates_;
    glm::dvec3 step_{0.0};
    std::vector<double> xs_, ys_, zs_;
    std::array<Plane, 4> planes_;         // plane k in slot k & 3
    std::array<PlaneEdges, 2> edges_;     // plane k's in slot k & 1
    std::vector<std::uint32_t> z_edges_;  // between planes k and k + 1: z_edges_[i + (n + 1) j]
    std::vector<std::uint8_t> configs_;   // of the row of cells at hand
    Mesh mesh_;
};

}  // namespace

Mesh grid_mesh(NativeBatch f, const Box& box, int cells, GridTimes* times) {
    const double start = times ? cpu_seconds() : 0.0;
    const double sampling = times ? times->sampling : 0.0;
    GridMesher mesher(f, box, cells, times);
    Mesh mesh = mesher.run();
    if (times) times->meshing += cpu_seconds() - start - (times->sampling - sampling);
    return mesh;
}

}  // namespace isomesh::bench
