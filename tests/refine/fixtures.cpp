#include "fixtures.h"

#include <cmath>
#include <map>
#include <stdexcept>

#include <glm/geometric.hpp>

#include "eval/tape_field.h"
#include "expr/compile.h"
#include "expr/parameters.h"
#include "mesh/topology.h"

namespace isomesh::test {
namespace {

class AnalyticEvaluator final : public Evaluator {
  public:
    explicit AnalyticEvaluator(AnalyticFunction f) : f_(std::move(f)) {}
    double value(const glm::dvec3& p) override { return f_.value(p); }
    void values(const PointBatch& points, std::span<double> out) override {
        for (std::size_t i = 0; i < points.size(); ++i)
            out[i] = f_.value({points.x[i], points.y[i], points.z[i]});
    }
    IntervalValue interval(const Box&) override { return {Interval::entire(), false, false}; }
    ValueGradient value_gradient(const glm::dvec3& p) override {
        return {f_.value(p), f_.gradient(p)};
    }
    IntervalGradient interval_gradient(const Box&) override {
        IntervalGradient g;
        g.value = {Interval::entire(), false, false};
        for (auto& c : g.gradient) c = Interval::entire();
        return g;
    }

  private:
    AnalyticFunction f_;  // a copy: an evaluator may outlive its field
};

class AnalyticField final : public Field {
  public:
    explicit AnalyticField(AnalyticFunction f) : f_(std::move(f)) {}
    std::unique_ptr<Evaluator> make_evaluator() const override {
        return std::make_unique<AnalyticEvaluator>(f_);
    }

  private:
    AnalyticFunction f_;
};

glm::dvec3 onto_surface_along_ray(const Field& field, const glm::dvec3& direction) {
    auto evaluator = field.make_evaluator();
    double lo = 0.0, hi = 1.0;
    while (evaluator->value(hi * direction) < 0.0) {
        hi *= 2.0;
        if (hi > 1e6) throw std::runtime_error("fixture: surface not star-shaped around 0");
    }
    for (int i = 0; i < 200 && hi - lo > 1e-15 * hi; ++i) {
        const double mid = 0.5 * (lo + hi);
        (evaluator->value(mid * direction) < 0.0 ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi) * direction;
}

// Face frames (normal axis, sign, u axis, v axis) with u x v pointing outward.
struct FaceFrame {
    int axis, sign, u, v;
};
constexpr FaceFrame kFaces[6] = {{0, +1, 1, 2}, {0, -1, 2, 1}, {1, +1, 2, 0},
                                 {1, -1, 0, 2}, {2, +1, 0, 1}, {2, -1, 1, 0}};

Mesh cube_mesh(const Field& field, int n, bool lower_half_only) {
    if (n < 1 || (lower_half_only && n % 2 != 0)) throw std::invalid_argument("cube_mesh: bad n");
    Mesh mesh;
    std::map<std::array<int, 3>, std::uint32_t> index;
    auto vertex = [&](const std::array<int, 3>& g) {
        auto [it, inserted] =
            index.try_emplace(g, static_cast<std::uint32_t>(mesh.positions.size()));
        if (inserted) {
            const glm::dvec3 d(-1.0 + 2.0 * g[0] / n, -1.0 + 2.0 * g[1] / n, -1.0 + 2.0 * g[2] / n);
            mesh.positions.push_back(onto_surface_along_ray(field, d));
            auto e = field.make_evaluator();
            mesh.normals.push_back(
                glm::normalize(e->value_gradient(mesh.positions.back()).gradient));
        }
        return it->second;
    };
    for (const FaceFrame& f : kFaces) {
        for (int a = 0; a < n; ++a) {
            for (int b = 0; b < n; ++b) {
                std::array<std::uint32_t, 4> q{};
                bool keep = true;
                const int corners[4][2] = {{a, b}, {a + 1, b}, {a + 1, b + 1}, {a, b + 1}};
                for (int c = 0; c < 4; ++c) {
                    std::array<int, 3> g{};
                    g[f.axis] = f.sign > 0 ? n : 0;
                    g[f.u] = corners[c][0];
                    g[f.v] = corners[c][1];
                    if (lower_half_only && g[2] > n / 2) keep = false;
                    if (keep) q[c] = vertex(g);
                }
                if (!keep) continue;
                // Alternate diagonals so that the mesh has no preferred direction.
                if ((a + b) % 2 == 0) {
                    mesh.triangles.push_back({q[0], q[1], q[2]});
                    mesh.triangles.push_back({q[0], q[2], q[3]});
                } else {
                    mesh.triangles.push_back({q[0], q[1], q[3]});
                    mesh.triangles.push_back({q[1], q[2], q[3]});
                }
            }
        }
    }
    build_adjacency(mesh);
    return mesh;
}

}  // namespace

std::shared_ptr<const Field> make_analytic_field(AnalyticFunction function) {
    return std::make_shared<AnalyticField>(std::move(function));
}

std::shared_ptr<const Field> make_quadric_field(const glm::dvec3& k, double c) {
    return make_analytic_field({[k, c](const glm::dvec3& p) {
                                    return k.x * p.x * p.x + k.y * p.y * p.y + k.z * p.z * p.z - c;
                                },
                                [k](const glm::dvec3& p) { return 2.0 * k * p; }});
}

std::shared_ptr<const Field> make_sphere_field(const glm::dvec3& center, double radius) {
    return make_analytic_field(
        {[center, radius](const glm::dvec3& p) { return glm::length(p - center) - radius; },
         [center](const glm::dvec3& p) {
             const glm::dvec3 d = p - center;
             const double l = glm::length(d);
             return l > 0.0 ? d / l : glm::dvec3(0.0);
         }});
}

std::shared_ptr<const Field> compile_field(
    const std::string& text, const std::map<std::string, double, std::less<>>& params) {
    CompileResult compiled = compile_expression(text);
    if (!compiled.ok()) throw std::invalid_argument(compiled.error->to_string());
    const ParameterBinding binding = bind_parameters(compiled.tape, params);
    if (!binding.ok()) throw std::invalid_argument(*binding.error);
    return make_tape_field(std::make_shared<const Tape>(std::move(compiled.tape)), binding.values);
}

Mesh cube_sphere_mesh(const Field& field, int n) {
    return cube_mesh(field, n, false);
}

Mesh half_cube_sphere_mesh(const Field& field, int n) {
    return cube_mesh(field, n, true);
}

std::string check_conforming(const Mesh& mesh, Boundary boundary) {
    const TopologyReport report = analyze_topology(mesh);
    if (report.nonmanifold_edges)
        return "non-manifold edges: " + std::to_string(report.nonmanifold_edges);
    if (report.nonmanifold_vertices)
        return "non-manifold vertices: " + std::to_string(report.nonmanifold_vertices);
    if (report.inconsistently_oriented_edges) return "inconsistent orientation";
    if (boundary == Boundary::None && report.boundary_edges)
        return "boundary edges (cracks or T-junctions): " + std::to_string(report.boundary_edges);
    if (mesh.neighbours.size() != mesh.triangles.size()) return "neighbours missing";
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        for (int e = 0; e < 3; ++e) {
            const std::uint32_t a = mesh.triangles[t][e], b = mesh.triangles[t][(e + 1) % 3];
            const std::uint32_t u = mesh.neighbours[t][e];
            if (u == kNoNeighbour) {
                if (boundary != Boundary::OnBoxFaces) continue;
                // A boundary edge must lie on a face of the box (an exactly shared coordinate);
                // anything else is a crack.
                const glm::dvec3 &pa = mesh.positions[a], &pb = mesh.positions[b];
                if (pa.x != pb.x && pa.y != pb.y && pa.z != pb.z)
                    return "boundary edge off the box faces at triangle " + std::to_string(t);
                continue;
            }
            bool back = false;
            for (int f = 0; f < 3; ++f)
                back = back || (mesh.triangles[u][f] == b && mesh.triangles[u][(f + 1) % 3] == a &&
                                mesh.neighbours[u][f] == t);
            if (!back) return "asymmetric neighbours at triangle " + std::to_string(t);
        }
    }
    return {};
}

std::size_t boundary_loops(const Mesh& mesh) {
    // Union-find over the vertices of boundary edges: each loop is one set.
    std::map<std::uint32_t, std::uint32_t> parent;
    auto find = [&](std::uint32_t v) {
        while (parent[v] != v) v = parent[v] = parent[parent[v]];
        return v;
    };
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        for (int e = 0; e < 3; ++e) {
            if (mesh.neighbours[t][e] != kNoNeighbour) continue;
            const std::uint32_t a = mesh.triangles[t][e], b = mesh.triangles[t][(e + 1) % 3];
            parent.try_emplace(a, a);
            parent.try_emplace(b, b);
            parent[find(a)] = find(b);
        }
    }
    std::size_t loops = 0;
    for (const auto& [v, p] : parent) loops += find(v) == v ? 1 : 0;
    return loops;
}

bool same_mesh(const Mesh& a, const Mesh& b) {
    return a.positions == b.positions && a.triangles == b.triangles;
}

Mesh replay_mesh(const MeshDelta& snapshot, const std::vector<MeshDelta>& deltas,
                 std::string* error) {
    DeltaMesh replica;
    std::string problem = replica.apply(snapshot);
    for (std::size_t i = 0; i < deltas.size() && problem.empty(); ++i)
        problem = replica.apply(deltas[i]);
    if (error) *error = problem;
    return replica.to_mesh();
}

Mesh canonical(const RefinedMesh& refined) {
    Mesh m;
    m.positions = refined.mesh.positions;
    m.normals = refined.mesh.normals;
    m.triangles = refined.mesh.triangles;
    return m;
}

}  // namespace isomesh::test
