// Error measures: epsilon_4 from the thesis (section 3.2.3), a first-order distance measure
// (Taubin, "Distance approximations for rasterizing implicit curves", ACM TOG 13(1), 1994: the
// distance to f = 0 is about |f| / |grad f|), and a sampling error report for finished meshes.
#include "refine/error_measures.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <vector>

#include <glm/geometric.hpp>

namespace isomesh {
namespace {

double first_order_distance(Evaluator& evaluator, const glm::dvec3& p) {
    const ValueGradient vg = evaluator.value_gradient(p);
    const double g = glm::length(vg.gradient);
    const double d = std::abs(vg.value) / g;
    return std::isfinite(d) ? d : 0.0;
}

double squared_length(const glm::dvec3& v) {
    return glm::dot(v, v);
}

double longest_edge(const TriangleGeometry& t) {
    return std::sqrt(std::max(
        {squared_length(t.b - t.a), squared_length(t.c - t.b), squared_length(t.a - t.c)}));
}

// Newton along the gradient first (it lands near the nearest point, which a distance needs), then
// the search line `hint` if that fails.
Projection nearest_surface_point(Evaluator& evaluator, const glm::dvec3& p, const glm::dvec3& hint,
                                 double scale, const ProjectionSettings& settings) {
    const Projection newton =
        project_to_surface(evaluator, {p, glm::dvec3(0.0), 0.0, scale, 0}, settings);
    if (newton.on_surface()) return newton;
    return project_to_surface(evaluator, {p, hint, 0.0, scale, 0}, settings);
}

}  // namespace

double epsilon4_error(const TriangleGeometry& t) {
    const double volume =
        std::abs(glm::dot(glm::cross(t.b - t.a, t.c - t.a), t.projected_midpoint - t.a)) / 6.0;
    return std::isfinite(volume) ? volume : 0.0;
}

void ErrorMeasure::triangle_errors(Evaluator& evaluator,
                                   std::span<const TriangleGeometry> triangles,
                                   std::span<double> errors) const {
    assert(triangles.size() == errors.size());
    for (std::size_t i = 0; i < triangles.size(); ++i)
        errors[i] = triangle_error(evaluator, triangles[i]);
}

void ErrorMeasure::errors_and_midpoint_values(Evaluator& evaluator,
                                              std::span<const TriangleGeometry> triangles,
                                              std::span<double> errors,
                                              std::span<double> midpoint_values) const {
    assert(triangles.size() == midpoint_values.size());
    triangle_errors(evaluator, triangles, errors);
    std::fill(midpoint_values.begin(), midpoint_values.end(),
              std::numeric_limits<double>::quiet_NaN());
}

namespace {

/// largest_sample_distances with x, y, z and f arrays of 2 * triangles.size() doubles for the
/// samples and their values.
[[gnu::always_inline]] inline void sample_distances(Evaluator& evaluator,
                                                    std::span<const TriangleGeometry> triangles,
                                                    std::span<double> distances,
                                                    std::span<double> midpoint_values,
                                                    double* __restrict x, double* __restrict y,
                                                    double* __restrict z, double* __restrict f) {
    // Two samples per triangle: the base midpoint and the centroid.
    for (std::size_t i = 0; i < triangles.size(); ++i) {
        const TriangleGeometry& t = triangles[i];
        const glm::dvec3 samples[2] = {0.5 * (t.a + t.b), (t.a + t.b + t.c) / 3.0};
        for (std::size_t k = 0; k < 2; ++k) {
            x[2 * i + k] = samples[k].x;
            y[2 * i + k] = samples[k].y;
            z[2 * i + k] = samples[k].z;
        }
    }
    const std::size_t n = 2 * triangles.size();
    evaluator.values({{x, n}, {y, n}, {z, n}}, {f, n});
    for (std::size_t i = 0; i < triangles.size(); ++i) {
        double distance = 0.0;
        const double g = triangles[i].gradient_norm;
        for (std::size_t k = 2 * i; k < 2 * i + 2; ++k) {
            const double d =
                g > 0.0 ? std::abs(f[k]) / g : first_order_distance(evaluator, {x[k], y[k], z[k]});
            if (std::isfinite(d)) distance = std::max(distance, d);
        }
        distances[i] = distance;
        if (!midpoint_values.empty()) midpoint_values[i] = f[2 * i];
    }
}

}  // namespace

void largest_sample_distances(Evaluator& evaluator, std::span<const TriangleGeometry> triangles,
                              std::span<double> distances, std::span<double> midpoint_values) {
    assert(triangles.size() == distances.size());
    assert(midpoint_values.empty() || midpoint_values.size() == triangles.size());
    // The refiner asks for a few triangles at a time, very often: their samples go on the stack.
    // More (a new mesh, a function change) go into vectors kept per thread, in one evaluation
    // call all the same (a call is the unit of work cancellation waits for).
    constexpr std::size_t kOnStack = 16;
    const std::size_t n = 2 * triangles.size();
    if (triangles.size() <= kOnStack) {
        double x[2 * kOnStack], y[2 * kOnStack], z[2 * kOnStack], f[2 * kOnStack];
        return sample_distances(evaluator, triangles, distances, midpoint_values, x, y, z, f);
    }
    thread_local std::vector<double> x, y, z, f;
    x.resize(n);
    y.resize(n);
    z.resize(n);
    f.resize(n);
    sample_distances(evaluator, triangles, distances, midpoint_values, x.data(), y.data(), z.data(),
                     f.data());
}

void DistanceError::triangle_errors(Evaluator& evaluator,
                                    std::span<const TriangleGeometry> triangles,
                                    std::span<double> errors) const {
    errors_and_midpoint_values(evaluator, triangles, errors, {});
}

void DistanceError::errors_and_midpoint_values(Evaluator& evaluator,
                                               std::span<const TriangleGeometry> triangles,
                                               std::span<double> errors,
                                               std::span<double> midpoint_values) const {
    largest_sample_distances(evaluator, triangles, errors, midpoint_values);
    for (std::size_t i = 0; i < triangles.size(); ++i) {
        const double error = errors[i] * longest_edge(triangles[i]);
        errors[i] = std::isfinite(error) ? error : 0.0;
    }
}

double DistanceError::triangle_error(Evaluator& evaluator, const TriangleGeometry& t) const {
    double error = 0.0;
    triangle_errors(evaluator, {&t, 1}, {&error, 1});
    return error;
}

void MaxDistanceError::triangle_errors(Evaluator& evaluator,
                                       std::span<const TriangleGeometry> triangles,
                                       std::span<double> errors) const {
    largest_sample_distances(evaluator, triangles, errors);
}

void MaxDistanceError::errors_and_midpoint_values(Evaluator& evaluator,
                                                  std::span<const TriangleGeometry> triangles,
                                                  std::span<double> errors,
                                                  std::span<double> midpoint_values) const {
    largest_sample_distances(evaluator, triangles, errors, midpoint_values);
}

double MaxDistanceError::triangle_error(Evaluator& evaluator, const TriangleGeometry& t) const {
    double error = 0.0;
    triangle_errors(evaluator, {&t, 1}, {&error, 1});
    return error;
}

std::shared_ptr<const ErrorMeasure> make_error_measure(std::string_view name) {
    if (name == "distance") return std::make_shared<DistanceError>();
    if (name == "epsilon4") return std::make_shared<Epsilon4Error>();
    if (name == "max_distance") return std::make_shared<MaxDistanceError>();
    return nullptr;
}

std::vector<std::string> error_measure_names() {
    return {"distance", "epsilon4", "max_distance"};
}

MeshErrorReport measure_mesh_error(const Mesh& mesh, Evaluator& evaluator, int samples_per_edge,
                                   const ProjectionSettings& projection) {
    MeshErrorReport report;
    const int n = std::max(samples_per_edge, 1);
    double distance_sum = 0.0;
    std::size_t distance_count = 0;
    double weighted_square_sum = 0.0;  // sum over triangles of area * mean squared distance
    double weighted_area = 0.0;
    for (const auto& tri : mesh.triangles) {
        const glm::dvec3 p[3] = {mesh.positions[tri[0]], mesh.positions[tri[1]],
                                 mesh.positions[tri[2]]};
        int base = 0;
        for (int e = 1; e < 3; ++e)
            if (squared_length(p[(e + 1) % 3] - p[e]) > squared_length(p[(base + 1) % 3] - p[base]))
                base = e;
        const glm::dvec3& a = p[base];
        const glm::dvec3& b = p[(base + 1) % 3];
        const glm::dvec3& c = p[(base + 2) % 3];
        const double scale = std::sqrt(squared_length(b - a));
        if (!(scale > 0.0)) continue;  // a degenerate triangle has no error and no samples
        const glm::dvec3 normal = glm::cross(b - a, c - a);
        const glm::dvec3 hint =
            mesh.normals.size() == mesh.positions.size()
                ? mesh.normals[tri[0]] + mesh.normals[tri[1]] + mesh.normals[tri[2]]
                : normal;
        const Projection mid =
            nearest_surface_point(evaluator, 0.5 * (a + b), hint, scale, projection);
        report.epsilon4_total += epsilon4_error({a, b, c, mid.position});
        double square_sum = 0.0;
        std::size_t samples = 0;
        for (int i = 0; i <= n; ++i) {
            for (int j = 0; i + j <= n; ++j) {
                const double u = double(i) / n, v = double(j) / n;
                const glm::dvec3 q = a + u * (b - a) + v * (c - a);
                const Projection proj =
                    nearest_surface_point(evaluator, q, hint, scale, projection);
                if (!proj.on_surface()) {
                    ++report.failed_projections;
                    continue;
                }
                const double d = glm::length(proj.position - q);
                report.max_distance = std::max(report.max_distance, d);
                distance_sum += d;
                ++distance_count;
                square_sum += d * d;
                ++samples;
            }
        }
        if (samples > 0) {
            const double area = 0.5 * glm::length(normal);
            weighted_square_sum += area * square_sum / double(samples);
            weighted_area += area;
        }
    }
    report.mean_distance = distance_count > 0 ? distance_sum / double(distance_count) : 0.0;
    report.rms_distance =
        weighted_area > 0.0 ? std::sqrt(weighted_square_sum / weighted_area) : 0.0;
    return report;
}

}  // namespace isomesh
