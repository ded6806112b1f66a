// Sampled scalar fields: a regular grid of samples (such as the .iso files of the Marching Cubes 33
// test suite) seen through the Field interface as its trilinear interpolant. The surface is f = 0
// (isovalue 0) with f > 0 outside, as for every field.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "eval/evaluator.h"

namespace isomesh {

/// nx x ny x nz samples on the corners of a regular grid spanning `box`: sample (i, j, k) sits at
/// box.lo + (i, j, k) * box.size() / (n - 1) and is samples[i + j * nx + k * nx * ny].
struct IsoGrid {
    int nx = 0, ny = 0, nz = 0;
    Box box;
    std::vector<float> samples;
};

/// Reads an .iso file (little endian: int32 nx, ny, nz; float32 xmin, xmax, ymin, ymax, zmin,
/// zmax; then nx * ny * nz float32 samples, x fastest). On failure returns nullopt and, when
/// `error` is not null, stores a message naming the problem (unreadable file, truncated header or
/// data, trailing bytes, or a grid validate_grid refuses). Never reads past what the file holds.
std::optional<IsoGrid> load_iso(const std::string& path, std::string* error);

/// Empty when `grid` can be made a field, else what is wrong. Requires 2 <= n <= 65536 samples on
/// each axis, a finite box with lo < hi on each axis, samples.size() == nx * ny * nz, and finite
/// samples.
std::string validate_grid(const IsoGrid& grid);

/// The trilinear interpolant of `grid`: NaN outside grid.box (its domain()). Intervals over a box
/// are the [min, max] of the samples of the cells the box overlaps (the interpolant is a convex
/// combination of its cell's corners), flagged maybe_undefined when the box leaves the grid.
/// Gradients are the interpolant's exact derivative; on a face between two cells, the cell on the
/// positive side (or the last cell) gives it. Interval gradients bound the cells' edge slopes.
/// Throws std::invalid_argument when validate_grid(grid) is not empty.
std::shared_ptr<const Field> make_grid_field(IsoGrid grid);

}  // namespace isomesh
