// Error measures: epsilon_4 from the thesis (section 3.2.3), a first-order distance measure
// (Taubin, "Distance approximations for rasterizing implicit curves", ACM TOG 13(1), 1994: the
// distance to f = 0 is about |f| / |grad f|), and a sampling error report for finished meshes.
#include "refine/error_measures.h"

#include <algorithm>
#include <cmath>

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

}  // namespace

double epsilon4_error(const TriangleGeometry& t) {
    const double volume =
        std::abs(glm::dot(glm::cross(t.b - t.a, t.c - t.a), t.projected_midpoint - t.a)) / 6.0;
    return std::isfinite(volume) ? volume : 0.0;
}

double largest_sample_distance(Evaluator& evaluator, const TriangleGeometry& t) {
    double distance = glm::length(t.projected_midpoint - 0.5 * (t.a + t.b));
    distance = std::max(distance, first_order_distance(evaluator, (t.a + t.b + t.c) / 3.0));
    distance = std::max(distance, first_order_distance(evaluator, 0.5 * (t.b + t.c)));
    distance = std::max(distance, first_order_distance(evaluator, 0.5 * (t.c + t.a)));
    return std::isfinite(distance) ? distance : 0.0;
}

double DistanceError::triangle_error(Evaluator& evaluator, const TriangleGeometry& t) const {
    const double longest = std::sqrt(std::max(
        {squared_length(t.b - t.a), squared_length(t.c - t.b), squared_length(t.a - t.c)}));
    const double error = largest_sample_distance(evaluator, t) * longest;
    return std::isfinite(error) ? error : 0.0;
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
            project_to_surface(evaluator, {0.5 * (a + b), hint, scale, -1}, projection);
        report.epsilon4_total += epsilon4_error({a, b, c, mid.position});
        for (int i = 0; i <= n; ++i) {
            for (int j = 0; i + j <= n; ++j) {
                const double u = double(i) / n, v = double(j) / n;
                const glm::dvec3 q = a + u * (b - a) + v * (c - a);
                const Projection proj =
                    project_to_surface(evaluator, {q, hint, scale, -1}, projection);
                if (!proj.on_surface()) {
                    ++report.failed_projections;
                    continue;
                }
                const double d = glm::length(proj.position - q);
                report.max_distance = std::max(report.max_distance, d);
                distance_sum += d;
                ++distance_count;
            }
        }
    }
    report.mean_distance = distance_count > 0 ? distance_sum / double(distance_count) : 0.0;
    return report;
}

}  // namespace isomesh
