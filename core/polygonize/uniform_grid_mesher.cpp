// Uniform-grid Marching Cubes 33 (Lorensen & Cline 1987 with Chernyaev's 1995 cases, mc33.h).
// Cells are visited one z-layer at a time; vertex ids of the grid edges live in per-layer arrays,
// so memory beyond the samples and the mesh is O(nx * ny).
#include "polygonize/uniform_grid_mesher.h"

#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "polygonize/mc33.h"

namespace isomesh {
namespace {

constexpr std::uint32_t kNoVertex = std::numeric_limits<std::uint32_t>::max();

void check_box(const Box& box) {
    for (int axis = 0; axis < 3; ++axis) {
        if (!std::isfinite(box.lo[axis]) || !std::isfinite(box.hi[axis]) ||
            !(box.lo[axis] < box.hi[axis])) {
            throw std::invalid_argument("meshing box must be finite with lo < hi on every axis");
        }
    }
}

class GridMesher {
  public:
    explicit GridMesher(const SampledGrid& grid)
        : g_(grid),
          layer_(static_cast<std::size_t>(grid.nx) * grid.ny),
          step_((grid.box.hi - grid.box.lo) / glm::dvec3(grid.nx - 1, grid.ny - 1, grid.nz - 1)) {}

    Mesh run() {
        // Edge vertex ids: x and y edges at the bottom and top of the current cell layer, and the
        // z edges between them, each indexed by the edge's lower grid point in its layer.
        for (auto& ids : bottom_) ids.assign(layer_, kNoVertex);
        for (auto& ids : top_) ids.assign(layer_, kNoVertex);
        vertical_.assign(layer_, kNoVertex);
        for (int k = 0; k + 1 < g_.nz; ++k) {
            for (int j = 0; j + 1 < g_.ny; ++j) {
                for (int i = 0; i + 1 < g_.nx; ++i) mesh_cell(i, j, k);
            }
            std::swap(bottom_, top_);
            for (auto& ids : top_) ids.assign(layer_, kNoVertex);
            vertical_.assign(layer_, kNoVertex);
        }
        return std::move(mesh_);
    }

  private:
    std::size_t index(int i, int j, int k) const {
        return static_cast<std::size_t>(i) +
               static_cast<std::size_t>(g_.nx) * (j + std::size_t(g_.ny) * k);
    }
    glm::dvec3 point(int i, int j, int k) const { return g_.box.lo + glm::dvec3(i, j, k) * step_; }

    /// Central (one-sided at the border) differences of the samples along each axis.
    glm::dvec3 gradient(int i, int j, int k) const {
        const int p[3] = {i, j, k}, n[3] = {g_.nx, g_.ny, g_.nz};
        glm::dvec3 result;
        for (int axis = 0; axis < 3; ++axis) {
            int lo[3] = {i, j, k}, hi[3] = {i, j, k};
            lo[axis] = std::max(p[axis] - 1, 0);
            hi[axis] = std::min(p[axis] + 1, n[axis] - 1);
            result[axis] =
                (g_.values[index(hi[0], hi[1], hi[2])] - g_.values[index(lo[0], lo[1], lo[2])]) /
                ((hi[axis] - lo[axis]) * step_[axis]);
        }
        return result;
    }

    static glm::dvec3 unit_or_zero(const glm::dvec3& v) {
        const double length = glm::length(v);
        return length > 0.0 && std::isfinite(length) ? v / length : glm::dvec3(0.0);
    }

    /// The vertex on the crossed edge e of cell (i, j, k), created by the first cell that needs it.
    std::uint32_t edge_vertex(int i, int j, int k, int e) {
        const int axis = e / 4, u = e & 1, v = (e >> 1) & 1;
        int offset[3] = {0, 0, 0};
        offset[axis == 0 ? 1 : 0] = u;
        offset[axis == 2 ? 1 : 2] = v;
        const int ci = i + offset[0], cj = j + offset[1], ck = k + offset[2];
        const std::size_t slot =
            static_cast<std::size_t>(ci) + static_cast<std::size_t>(g_.nx) * cj;
        std::uint32_t& id = axis == 2 ? vertical_[slot] : (ck == k ? bottom_ : top_)[axis][slot];
        if (id != kNoVertex) return id;

        int end[3] = {ci, cj, ck};
        ++end[axis];
        const double f0 = g_.values[index(ci, cj, ck)],
                     f1 = g_.values[index(end[0], end[1], end[2])];
        const double t = f0 / (f0 - f1);  // f0 and f1 differ in sign, so f0 != f1
        id = static_cast<std::uint32_t>(mesh_.positions.size());
        mesh_.positions.push_back(point(ci, cj, ck) +
                                  t * (point(end[0], end[1], end[2]) - point(ci, cj, ck)));
        mesh_.normals.push_back(
            unit_or_zero((1.0 - t) * gradient(ci, cj, ck) + t * gradient(end[0], end[1], end[2])));
        return id;
    }

    void mesh_cell(int i, int j, int k) {
        std::array<double, 8> f;
        for (int c = 0; c < 8; ++c) {
            f[c] = g_.values[index(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1))];
            if (!std::isfinite(f[c])) return;
        }
        const CellTriangulation cell = triangulate_cell(f);
        if (cell.triangle_count == 0) return;
        std::array<std::uint32_t, 13> ids;
        ids.fill(kNoVertex);
        for (int t = 0; t < cell.triangle_count; ++t) {
            for (std::uint8_t v : cell.triangles[t]) {
                if (v != kInteriorVertex && ids[v] == kNoVertex) ids[v] = edge_vertex(i, j, k, v);
            }
        }
        if (cell.uses_interior_vertex()) ids[kInteriorVertex] = interior_vertex(cell, ids, i, j, k);
        for (int t = 0; t < cell.triangle_count; ++t) {
            const auto& tri = cell.triangles[t];
            mesh_.triangles.push_back({ids[tri[0]], ids[tri[1]], ids[tri[2]]});
        }
    }

    std::uint32_t interior_vertex(const CellTriangulation& cell, std::array<std::uint32_t, 13>& ids,
                                  int i, int j, int k) {
        glm::dvec3 position(0.0), normal(0.0);
        int count = 0;
        for (int e = 0; e < 12; ++e) {
            if (!((cell.interior_vertex_edges >> e) & 1u)) continue;
            if (ids[e] == kNoVertex) ids[e] = edge_vertex(i, j, k, e);
            position += mesh_.positions[ids[e]];
            normal += mesh_.normals[ids[e]];
            ++count;
        }
        mesh_.positions.push_back(position / static_cast<double>(count));
        mesh_.normals.push_back(unit_or_zero(normal));
        return static_cast<std::uint32_t>(mesh_.positions.size() - 1);
    }

    const SampledGrid& g_;
    std::size_t layer_;
    glm::dvec3 step_;
    std::array<std::vector<std::uint32_t>, 2> bottom_, top_;  // [axis x or y][slot]
    std::vector<std::uint32_t> vertical_;
    Mesh mesh_;
};

}  // namespace

Mesh mesh_sampled_grid(const SampledGrid& grid) {
    if (grid.nx < 2 || grid.ny < 2 || grid.nz < 2) {
        throw std::invalid_argument("a sampled grid needs at least 2 samples per axis");
    }
    const std::size_t expected = static_cast<std::size_t>(grid.nx) * grid.ny * grid.nz;
    if (grid.values.size() != expected) {
        throw std::invalid_argument("sampled grid has " + std::to_string(grid.values.size()) +
                                    " values, expected " + std::to_string(expected));
    }
    check_box(grid.box);
    return GridMesher(grid).run();
}

Mesh mesh_uniform_grid(Evaluator& evaluator, const Box& box, int cells_per_axis) {
    if (cells_per_axis < 1) throw std::invalid_argument("cells_per_axis must be at least 1");
    check_box(box);
    const int n = cells_per_axis + 1;
    const glm::dvec3 step = box.size() / static_cast<double>(cells_per_axis);
    std::vector<double> values(static_cast<std::size_t>(n) * n * n);
    // One batch per z-layer: n * n points.
    std::vector<double> xs(static_cast<std::size_t>(n) * n), ys(xs.size()), zs(xs.size());
    for (int k = 0; k < n; ++k) {
        for (int j = 0; j < n; ++j) {
            for (int i = 0; i < n; ++i) {
                const std::size_t p = static_cast<std::size_t>(i) + static_cast<std::size_t>(n) * j;
                xs[p] = box.lo.x + i * step.x;
                ys[p] = box.lo.y + j * step.y;
                zs[p] = box.lo.z + k * step.z;
            }
        }
        evaluator.values(
            PointBatch{xs, ys, zs},
            std::span<double>(values).subspan(static_cast<std::size_t>(k) * n * n, xs.size()));
    }
    return mesh_sampled_grid(SampledGrid{n, n, n, box, values});
}

}  // namespace isomesh
