// The thesis's showcase, the blobby cube |r| + 2 cos 2x + 2 cos 2y + 2 cos 2z = 20 on [-28, 28]^3:
// its converged mesh has the surface's exact topology, every small bubble included. The reference
// is derived without any mesher, from the critical points of f (Morse theory):
// - the region f <= 0 is a compact 3-manifold inside the box whose boundary is the surface, so
//   chi(surface) = 2 chi(f <= 0) = 2 sum over the critical points p with f(p) < 0 of (-1)^index(p)
//   (f is a Morse function here: every critical point is non-degenerate, none at level 0);
// - every local minimum p with f(p) < 0 is inside the mesh, or, where the bubble around it is
//   smaller than the mesh's triangles (a bubble of radius 0.06 meshed with a few triangles need
//   not contain its centre), has a mesh vertex within twice that radius, sqrt(2 |f(p)| / lambda)
//   along its flattest direction (lambda the smallest eigenvalue of the Hessian): no bubble is
//   missed.
// The critical points of f are those of the cosine part, 2 cos 2x_i having its extrema at
// x_i = k pi / 2, moved slightly by the term |r| (its gradient has length 1, the cosines' second
// derivatives are +-8): Newton's method from each point k pi / 2 finds each one. Except near the
// origin, where |r| is not smooth: f ~ -14 + r - 4 r^2 has its cone tip there (a minimum) and a
// shell of critical points at r ~ 1/8 (26 of them: maxima, saddles), found by Newton's method
// from a dense grid of starting points.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <numbers>
#include <optional>
#include <set>
#include <tuple>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>

#include "mesh/topology.h"
#include "progressive/pipeline.h"
#include "support/mesh_checks.h"

namespace isomesh {
namespace {

constexpr double kHalfSize = 28.0;

double f(const glm::dvec3& p) {
    return glm::length(p) + 2 * std::cos(2 * p.x) + 2 * std::cos(2 * p.y) + 2 * std::cos(2 * p.z) -
           20;
}

glm::dvec3 gradient(const glm::dvec3& p) {
    const double r = glm::length(p);
    return p / r - 4.0 * glm::dvec3(std::sin(2 * p.x), std::sin(2 * p.y), std::sin(2 * p.z));
}

glm::dmat3 hessian(const glm::dvec3& p) {
    const double r = glm::length(p);
    glm::dmat3 h = glm::outerProduct(p, p) * (-1.0 / (r * r * r));
    for (int i = 0; i < 3; ++i) h[i][i] += 1.0 / r - 8.0 * std::cos(2 * p[i]);
    return h;
}

/// Negative eigenvalues of a symmetric 3x3 matrix: by Sylvester's law of inertia, the number of
/// sign changes in the sequence 1, D1, D2, D3 of leading principal minors (all non-zero here).
int morse_index(const glm::dmat3& h) {
    const double d1 = h[0][0];
    const double d2 = h[0][0] * h[1][1] - h[0][1] * h[1][0];
    const double d3 = glm::determinant(h);
    int changes = 0;
    double previous = 1.0;
    for (double d : {d1, d2, d3}) {
        if ((d < 0) != (previous < 0)) ++changes;
        previous = d;
    }
    return changes;
}

struct CriticalPoint {
    glm::dvec3 position;
    double value;
    int index;
};

/// The radius of the bubble around a minimum p: where f(p) + lambda d^2 / 2 reaches 0, lambda
/// the smallest eigenvalue of the Hessian (bounded below by its Gershgorin discs).
double bubble_radius(const CriticalPoint& minimum) {
    const glm::dmat3 h = hessian(minimum.position);
    double lambda = INFINITY;
    for (int i = 0; i < 3; ++i) {
        double disc = 0.0;
        for (int j = 0; j < 3; ++j)
            if (j != i) disc += std::abs(h[i][j]);
        lambda = std::min(lambda, h[i][i] - disc);
    }
    return std::sqrt(2.0 * std::abs(minimum.value) / std::max(lambda, 1e-6));
}

double nearest_vertex(const Mesh& mesh, const glm::dvec3& p) {
    double best = INFINITY;
    for (const glm::dvec3& v : mesh.positions) best = std::min(best, glm::length(v - p));
    return best;
}

/// Newton's method on grad f = 0 from `start`.
std::optional<glm::dvec3> newton(glm::dvec3 p) {
    for (int iteration = 0; iteration < 60; ++iteration) {
        const glm::dvec3 step = glm::inverse(hessian(p)) * gradient(p);
        p -= step;
        if (glm::length(step) < 1e-13) return p;
    }
    return std::nullopt;
}

class CriticalPoints {
  public:
    /// Adds the critical point Newton's method reaches from `start`, if within `reach` of it.
    void search(const glm::dvec3& start, double reach) {
        const std::optional<glm::dvec3> p = newton(start);
        if (!p || glm::length(*p - start) > reach || glm::length(*p) < 1e-9) return;
        if (std::abs(p->x) >= kHalfSize || std::abs(p->y) >= kHalfSize ||
            std::abs(p->z) >= kHalfSize)
            return;
        const auto key = std::make_tuple(std::lround(p->x * 1e7), std::lround(p->y * 1e7),
                                         std::lround(p->z * 1e7));
        if (!seen_.insert(key).second) return;
        const double value = f(*p);
        if (value < 0.0) points.push_back({*p, value, morse_index(hessian(*p))});
    }
    std::vector<CriticalPoint> points;

  private:
    std::set<std::tuple<long, long, long>> seen_;
};

std::vector<CriticalPoint> critical_points_below_zero() {
    CriticalPoints found;
    const double h = std::numbers::pi / 2;
    const int k = static_cast<int>(std::floor(kHalfSize / h));
    for (int a = -k; a <= k; ++a)
        for (int b = -k; b <= k; ++b)
            for (int c = -k; c <= k; ++c)
                if (a != 0 || b != 0 || c != 0) found.search({a * h, b * h, c * h}, 0.5);
    // Around the origin's cone tip (off-lattice starting points, none at the tip itself).
    constexpr int n = 30;
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b)
            for (int c = 0; c < n; ++c)
                found.search({-0.45 + 0.9 * (a + 0.37) / n, -0.45 + 0.9 * (b + 0.61) / n,
                              -0.45 + 0.9 * (c + 0.13) / n},
                             0.5);
    return found.points;
}

/// Whether `p` is inside the closed mesh: the parity of the crossings of a ray (in a direction no
/// edge of this lattice-like mesh is parallel to) with its triangles (Moller-Trumbore).
bool inside(const Mesh& mesh, const glm::dvec3& p) {
    const glm::dvec3 d = glm::normalize(glm::dvec3(0.5773, 0.3141, 0.7071));
    int crossings = 0;
    for (const auto& t : mesh.triangles) {
        const glm::dvec3 a = mesh.positions[t[0]], e1 = mesh.positions[t[1]] - a,
                         e2 = mesh.positions[t[2]] - a;
        const glm::dvec3 q = glm::cross(d, e2);
        const double det = glm::dot(e1, q);
        if (std::abs(det) < 1e-300) continue;
        const glm::dvec3 s = p - a;
        const double u = glm::dot(s, q) / det;
        if (u < 0.0 || u > 1.0) continue;
        const glm::dvec3 r = glm::cross(s, e1);
        const double v = glm::dot(d, r) / det;
        if (v < 0.0 || u + v > 1.0) continue;
        if (glm::dot(e2, r) / det > 0.0) ++crossings;
    }
    return crossings % 2 == 1;
}

TEST(PipelineBlobbyCube, converged_mesh_has_the_exact_topology_every_bubble_found) {
    const std::vector<CriticalPoint> critical = critical_points_below_zero();
    long chi_region = 1;  // the origin: a minimum of f (|r| has its cone tip there)
    std::vector<CriticalPoint> minima{{glm::dvec3(0.0), f(glm::dvec3(0.0)), 0}};
    for (const CriticalPoint& c : critical) {
        chi_region += c.index % 2 == 0 ? 1 : -1;
        if (c.index == 0) minima.push_back(c);
    }
    std::printf("critical points with f < 0: %zu, %zu minima; chi(surface) = %ld\n",
                critical.size() + 1, minima.size(), 2 * chi_region);

    PipelineSettings settings;
    settings.phase1.box = {glm::dvec3(-kHalfSize), glm::dvec3(kHalfSize)};
    settings.phase1.threads = 0;
    settings.refine.constraint = Constraint::triangle_budget(20000);
    Pipeline pipeline(test::field_of("sqrt(x^2+y^2+z^2)+2cos(2x)+2cos(2y)+2cos(2z)=20"), settings);
    pipeline.run_to_convergence();
    const Mesh mesh = pipeline.mesh().mesh;
    const TopologyReport report = analyze_topology(mesh);
    std::printf("mesh: %zu triangles, %zu components, chi = %ld, unresolved cells %zu\n",
                report.triangles, report.components, report.euler_characteristic,
                pipeline.status().unresolved_cells);
    EXPECT_TRUE(report.watertight());
    EXPECT_TRUE(report.manifold());
    EXPECT_EQ(report.euler_characteristic, 2 * chi_region);
    std::size_t missed = 0, small = 0;
    for (const CriticalPoint& m : minima) {
        if (inside(mesh, m.position)) continue;
        ++small;
        missed += nearest_vertex(mesh, m.position) > 2.0 * bubble_radius(m);
    }
    std::printf("%zu minima in bubbles smaller than the triangles\n", small);
    EXPECT_EQ(missed, 0u) << "local minima with f < 0 and no surface around them";
}

}  // namespace
}  // namespace isomesh
