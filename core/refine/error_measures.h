// Error measures (thesis Definition 13: a map from triangles to non-negative reals): the split
// priority of every triangle, and the quantities constraints bound.
//
// - "epsilon4" (the thesis's epsilon_4, section 3.2.3): the volume of the tetrahedron spanned by
//   the triangle and the projection of its base edge's midpoint onto the surface. It costs nothing
//   beyond that projection, which is the vertex a split creates anyway, and it approximates the
//   volume between triangle and surface (the thesis's target measure epsilon_G).
// - "distance": the triangle's area times the largest first-order distance |f| / |grad f| to the
//   surface at four points (the base midpoint, where the exact distance to its projection is used,
//   the centroid and the two other edge midpoints). Also a volume, but it sees bulges away from the
//   base edge that epsilon4 misses (epsilon4 is zero when the projected midpoint lies in the
//   triangle's plane, whatever the surface does elsewhere); three more gradient evaluations per
//   triangle.
//
// The default is epsilon4: the thesis's measure, whose table we reproduce, and the cheaper one.
// The accuracy test prints both against uniform Marching Cubes (see the refiner report).
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <glm/vec3.hpp>

#include "eval/evaluator.h"
#include "mesh/mesh.h"
#include "refine/surface_projection.h"

namespace isomesh {

/// A triangle seen by an error measure: a-b is its base edge (a, b, c counter-clockwise), and
/// projected_midpoint is the base midpoint (a + b) / 2 moved onto the surface.
struct TriangleGeometry {
    glm::dvec3 a{0.0};
    glm::dvec3 b{0.0};
    glm::dvec3 c{0.0};
    glm::dvec3 projected_midpoint{0.0};
};

class ErrorMeasure {
  public:
    virtual ~ErrorMeasure() = default;
    virtual std::string_view name() const = 0;
    /// The triangle's error, >= 0 (0 when it cannot be computed). Deterministic: the same
    /// geometry and function give the same value.
    virtual double triangle_error(Evaluator& evaluator, const TriangleGeometry& triangle) const = 0;
};

/// epsilon_4: |det(b - a, c - a, m - a)| / 6 with m the projected midpoint.
double epsilon4_error(const TriangleGeometry& triangle);

class Epsilon4Error final : public ErrorMeasure {
  public:
    std::string_view name() const override { return "epsilon4"; }
    double triangle_error(Evaluator&, const TriangleGeometry& triangle) const override {
        return epsilon4_error(triangle);
    }
};

class DistanceError final : public ErrorMeasure {
  public:
    std::string_view name() const override { return "distance"; }
    double triangle_error(Evaluator& evaluator, const TriangleGeometry& triangle) const override;
};

/// The measure called `name` ("epsilon4" or "distance"), or nullptr for an unknown name.
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
    /// Samples whose projection failed (they are left out of the distances).
    std::size_t failed_projections = 0;
};

MeshErrorReport measure_mesh_error(const Mesh& mesh, Evaluator& evaluator, int samples_per_edge = 4,
                                   const ProjectionSettings& projection = {});

}  // namespace isomesh
