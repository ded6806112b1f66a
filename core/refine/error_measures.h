// Error measures (thesis Definition 13: a map from triangles to non-negative reals): the split
// priority of every triangle, and the quantities constraints bound.
//
// - "epsilon4" (the thesis's epsilon_4, section 3.2.3): the volume of the tetrahedron spanned by
//   the triangle and the projection of its base edge's midpoint onto the surface. It costs nothing
//   beyond that projection, which is the vertex a split creates anyway, and it approximates the
//   volume between triangle and surface (the thesis's target measure epsilon_G).
// - "distance": the largest first-order distance |f| / |grad f| to the surface (Taubin 1994) at the
//   base midpoint and the centroid, times the triangle's longest edge. A strip of surface along
//   the triangle rather than a volume: a long thin triangle (Marching Cubes makes many) has a small
//   volume but can lie far from the surface, and epsilon4 leaves it alone. |grad f| is the mean of
//   its values at the corners (known from their projection), so the measure costs two plain
//   evaluations of f and no projection: the base midpoint is projected only when the triangle is
//   split.
// - "max_distance": that largest distance alone (a Hausdorff-like bound, convergent but blind to
//   size: it spends triangles on the worst spot whatever its extent).
//
// The default is "distance". Measured against uniform Marching Cubes at equal triangle counts
// (tests/refine/accuracy_test.cpp): it matches epsilon4 on total epsilon4 error (within 5%) and
// cuts the maximum distance to the surface by 20-40%, at lower cost; "max_distance" cuts the
// maximum distance a little further but raises the total error by up to 30%.
#pragma once

#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/vec3.hpp>

#include "eval/evaluator.h"
#include "mesh/mesh.h"
#include "refine/surface_projection.h"

namespace isomesh {

/// A triangle seen by an error measure: a-b is its base edge (a, b, c counter-clockwise).
struct TriangleGeometry {
    glm::dvec3 a{0.0};
    glm::dvec3 b{0.0};
    glm::dvec3 c{0.0};
    /// The base midpoint (a + b) / 2 moved onto the surface; set only for measures whose
    /// needs_projected_midpoint() is true.
    glm::dvec3 projected_midpoint{0.0};
    /// The mean of |grad f| at the corners, or 0 when unknown.
    double gradient_norm = 0.0;
};

class ErrorMeasure {
  public:
    virtual ~ErrorMeasure() = default;
    virtual std::string_view name() const = 0;
    /// Whether triangle_error reads TriangleGeometry::projected_midpoint.
    virtual bool needs_projected_midpoint() const { return false; }
    /// The triangle's error, >= 0 (0 when it cannot be computed). Deterministic: the same
    /// geometry and function give the same value.
    virtual double triangle_error(Evaluator& evaluator, const TriangleGeometry& triangle) const = 0;
    /// errors[i] = triangle_error(evaluator, triangles[i]), bit for bit; measures that evaluate f
    /// override it to batch their evaluations (Evaluator::values). Precondition: equal sizes.
    virtual void triangle_errors(Evaluator& evaluator, std::span<const TriangleGeometry> triangles,
                                 std::span<double> errors) const;
    /// triangle_errors, and midpoint_values[i] = f((a + b) / 2) of triangles[i] where the
    /// measure evaluated f there (bit for bit Evaluator::value's), NaN elsewhere: the refiner
    /// projects that midpoint when it splits the triangle, and starts from the value. The default
    /// gives NaN. Precondition: equal sizes.
    virtual void errors_and_midpoint_values(Evaluator& evaluator,
                                            std::span<const TriangleGeometry> triangles,
                                            std::span<double> errors,
                                            std::span<double> midpoint_values) const;
};

/// epsilon_4: |det(b - a, c - a, m - a)| / 6 with m the projected midpoint.
double epsilon4_error(const TriangleGeometry& triangle);

class Epsilon4Error final : public ErrorMeasure {
  public:
    std::string_view name() const override { return "epsilon4"; }
    bool needs_projected_midpoint() const override { return true; }
    double triangle_error(Evaluator&, const TriangleGeometry& triangle) const override {
        return epsilon4_error(triangle);
    }
};

/// distances[i] = the larger first-order distance to the surface at the base midpoint and the
/// centroid of triangles[i], from one batched evaluation where the gradient norm is known; and,
/// when midpoint_values is not empty, midpoint_values[i] = f at that base midpoint.
void largest_sample_distances(Evaluator& evaluator, std::span<const TriangleGeometry> triangles,
                              std::span<double> distances, std::span<double> midpoint_values = {});

class DistanceError final : public ErrorMeasure {
  public:
    std::string_view name() const override { return "distance"; }
    double triangle_error(Evaluator& evaluator, const TriangleGeometry& triangle) const override;
    void triangle_errors(Evaluator& evaluator, std::span<const TriangleGeometry> triangles,
                         std::span<double> errors) const override;
    void errors_and_midpoint_values(Evaluator& evaluator,
                                    std::span<const TriangleGeometry> triangles,
                                    std::span<double> errors,
                                    std::span<double> midpoint_values) const override;
};

class MaxDistanceError final : public ErrorMeasure {
  public:
    std::string_view name() const override { return "max_distance"; }
    double triangle_error(Evaluator& evaluator, const TriangleGeometry& triangle) const override;
    void triangle_errors(Evaluator& evaluator, std::span<const TriangleGeometry> triangles,
                         std::span<double> errors) const override;
    void errors_and_midpoint_values(Evaluator& evaluator,
                                    std::span<const TriangleGeometry> triangles,
                                    std::span<double> errors,
                                    std::span<double> midpoint_values) const override;
};

/// The measure called `name` ("distance", "epsilon4", "max_distance"), or nullptr for an unknown
/// name.
std::shared_ptr<const ErrorMeasure> make_error_measure(std::string_view name);
/// The names make_error_measure accepts, the default first.
std::vector<std::string> error_measure_names();

/// Errors of a finished mesh, measured the same way for any mesher (used to compare the refiner
/// with Marching Cubes).
struct MeshErrorReport {
    /// Sum of epsilon_4 over triangles, each triangle's longest edge taken as its base edge.
    double epsilon4_total = 0.0;
    /// Largest distance from a sample point of a triangle to its projection onto the surface
    /// (samples on a barycentric grid with `samples_per_edge` + 1 points per edge).
    double max_distance = 0.0;
    /// Mean of those distances over all samples.
    double mean_distance = 0.0;
    /// Root mean square of those distances, area-weighted: each triangle's mean squared sample
    /// distance weighted by its area, so that it estimates the rms distance over the surface of
    /// the mesh whatever the triangles' sizes (the measure that compares meshers at equal
    /// accuracy: bench/bench_pipeline.cpp).
    double rms_distance = 0.0;
    /// Samples whose projection failed (they are left out of the distances).
    std::size_t failed_projections = 0;
};

MeshErrorReport measure_mesh_error(const Mesh& mesh, Evaluator& evaluator, int samples_per_edge = 4,
                                   const ProjectionSettings& projection = {});

}  // namespace isomesh
