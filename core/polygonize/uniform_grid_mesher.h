// Marching Cubes 33 over a uniform grid of samples: the "uniform Marching Cubes" baseline that the
// octree polygonizer is measured against, and the mesher of sampled volumes in tests.
#pragma once

#include <span>

#include "eval/evaluator.h"
#include "mesh/mesh.h"

namespace isomesh {

/// nx * ny * nz samples at the points of a regular grid spanning `box` (corners included):
/// sample (i, j, k) is at box.lo + (i / (nx - 1), j / (ny - 1), k / (nz - 1)) * box.size(), and
/// its value is values[i + nx * (j + ny * k)] (x fastest).
struct SampledGrid {
    int nx = 0, ny = 0, nz = 0;
    Box box;
    std::span<const double> values;
};

/// The MC33 mesh of the grid's trilinear interpolant at value 0, inside negative:
/// - one vertex per crossed grid edge, at the linear-interpolation crossing, shared by the cells
///   around the edge; one interior vertex per cell whose MC33 subcase needs one;
/// - normals from central differences of the samples, interpolated along the edge;
/// - triangles counter-clockwise seen from outside (f > 0);
/// - watertight, except where the surface leaves the box and around skipped cells: a cell with a
///   non-finite sample (NaN where f is undefined) is skipped.
/// Throws std::invalid_argument if a dimension is < 2, values.size() != nx * ny * nz, or the
/// box is not finite with lo < hi on every axis.
Mesh mesh_sampled_grid(const SampledGrid& grid);

/// Samples the field of `evaluator` on (cells_per_axis + 1)^3 points over `box` with batched
/// Evaluator::values calls, then meshes them with mesh_sampled_grid. Throws std::invalid_argument
/// if cells_per_axis < 1 or the box is invalid (as above).
Mesh mesh_uniform_grid(Evaluator& evaluator, const Box& box, int cells_per_axis);

}  // namespace isomesh
