// Phase 1 speed and accuracy: the octree polygonizer against uniform Marching Cubes 33
// (polygonize/uniform_grid_mesher.h) at the resolution that gives about the same triangle count.
// - octree/<surface>: time to the first mesh with the default settings, one thread (thread CPU
//   time: the machine is shared). Counters: triangles, evaluations per triangle.
//   octree_all_threads/thesis_sphere: the same with every hardware thread (wall-clock).
// - uniform/<surface>: sampling (batched) and meshing the uniform grid of n^3 cells, n chosen so
//   the triangle count is closest to the octree's.
// Printed after the run, per surface: both times and the ratio uniform / octree, and the accuracy
// of both meshes at equal triangle count: max and mean of |f| / |grad f| (a first-order distance to
// the surface) at the vertices and at the triangles' centroids, relative to the box's diagonal,
// and the topology each mesh has (the octree's is the gallery's expected one).
// The thesis's figure for |r| = c at about 2,000 triangles is 9 ms.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "bench_clock.h"
#include "eval/tape_field.h"
#include "expr/compile.h"
#include "mesh/topology.h"
#include "polygonize/polygonizer.h"
#include "polygonize/uniform_grid_mesher.h"

namespace isomesh {
namespace {

using bench::cpu_seconds;
using bench::wall_seconds;

struct Surface {
    const char* name;
    const char* expression;
};

// The thesis's sphere |r| = c with c tuned to about 2,000 triangles at the default settings, and
// the gallery of tests/polygonize (those with a surface in the default box).
const Surface kSurfaces[] = {
    {"thesis_sphere", "sqrt(x^2+y^2+z^2)=4.65"},
    {"sphere", "x^2+y^2+z^2=4"},
    {"ellipsoid", "10x^2+y^2+z^2=20"},
    {"cosine_sphere", "x^2+y^2+z^2+2cos(2x)=5"},
    {"torus", "(sqrt(x^2+y^2)-2)^2+z^2=0.64"},
    {"genus_two", "(x(x-1)^2(x-2)+y^2)^2+z^2=0.02"},
    {"tanglecube", "x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8=0"},
    {"touching_spheres", "min((x-1.01)^2+y^2+z^2, (x+1.01)^2+y^2+z^2)=1"},
    {"tiny_sphere", "(x-0.123)^2+(y+0.234)^2+(z-0.345)^2=0.0025"},
    {"gyroid", "sin(x)cos(y)+sin(y)cos(z)+sin(z)cos(x)=0"},
};

const Box kBox{{-5.0, -5.0, -5.0}, {5.0, 5.0, 5.0}};

std::shared_ptr<const Field> field_of(const char* expression) {
    return make_tape_field(std::make_shared<const Tape>(compile_expression(expression).tape), {});
}

struct Measure {
    double seconds = 0.0;
    std::size_t triangles = 0;
    std::size_t evaluations = 0;
    int cells_per_axis = 0;  // uniform only
};

std::map<std::string, Measure>& measures() {
    static std::map<std::string, Measure> m;
    return m;
}

PolygonizeResult octree(const Field& field, int threads) {
    PolygonizeSettings settings;
    settings.threads = threads;
    return polygonize(field, settings);
}

Mesh uniform(const Field& field, int n) {
    auto evaluator = field.make_evaluator();
    return mesh_uniform_grid(*evaluator, kBox, n);
}

/// The uniform resolution whose triangle count is closest to `target` (the count grows about
/// as n^2: doubling, then bisection on n).
int matching_resolution(const Field& field, std::size_t target) {
    int lo = 1, hi = 4;
    while (hi < 1024 && uniform(field, hi).triangle_count() < target) {
        lo = hi;
        hi *= 2;
    }
    while (hi - lo > 1) {
        const int mid = (lo + hi) / 2;
        (uniform(field, mid).triangle_count() < target ? lo : hi) = mid;
    }
    const auto gap = [&](int n) {
        const double t = double(uniform(field, n).triangle_count());
        return std::abs(t - double(target));
    };
    return gap(lo) <= gap(hi) ? lo : hi;
}

void BM_octree(benchmark::State& state, const Surface* surface, int threads) {
    const auto field = field_of(surface->expression);
    double total = 0.0;
    PolygonizeResult result;
    for (auto _ : state) {
        const double start = threads == 1 ? cpu_seconds() : wall_seconds();
        result = octree(*field, threads);
        total += (threads == 1 ? cpu_seconds() : wall_seconds()) - start;
        benchmark::DoNotOptimize(result.mesh.positions.data());
    }
    const double triangles = double(result.stats.triangles);
    state.counters["triangles"] = triangles;
    state.counters["evaluations_per_triangle"] =
        triangles > 0 ? double(result.stats.evaluations) / triangles : 0.0;
    state.counters["depth"] = result.stats.depth;
    const std::string key =
        std::string(threads == 1 ? "octree/" : "octree_all_threads/") + surface->name;
    measures()[key] = {total / double(state.iterations()), result.stats.triangles,
                       result.stats.evaluations, 0};
}

void BM_uniform(benchmark::State& state, const Surface* surface) {
    const auto field = field_of(surface->expression);
    const std::size_t target = std::max<std::size_t>(1, octree(*field, 1).stats.triangles);
    const int n = matching_resolution(*field, target);
    double total = 0.0;
    Mesh mesh;
    for (auto _ : state) {
        const double start = cpu_seconds();
        mesh = uniform(*field, n);
        total += cpu_seconds() - start;
        benchmark::DoNotOptimize(mesh.positions.data());
    }
    state.counters["triangles"] = double(mesh.triangle_count());
    state.counters["cells_per_axis"] = n;
    const double evaluations = std::pow(n + 1.0, 3.0);
    state.counters["evaluations_per_triangle"] =
        mesh.triangle_count() > 0 ? evaluations / double(mesh.triangle_count()) : 0.0;
    measures()[std::string("uniform/") + surface->name] = {
        total / double(state.iterations()), mesh.triangle_count(),
        static_cast<std::size_t>(evaluations), n};
}

struct Accuracy {
    double vertex_max = 0.0, vertex_mean = 0.0, centroid_max = 0.0, centroid_mean = 0.0;
};

double relative_distance(Evaluator& evaluator, const glm::dvec3& p) {
    const ValueGradient vg = evaluator.value_gradient(p);
    const double g = glm::length(vg.gradient);
    if (vg.value == 0.0) return 0.0;
    return (g > 0.0 ? std::abs(vg.value) / g : INFINITY) / glm::length(kBox.size());
}

Accuracy accuracy(const Field& field, const Mesh& mesh) {
    auto evaluator = field.make_evaluator();
    Accuracy a;
    for (const glm::dvec3& p : mesh.positions) {
        const double d = relative_distance(*evaluator, p);
        a.vertex_max = std::max(a.vertex_max, d);
        a.vertex_mean += d;
    }
    for (const auto& t : mesh.triangles) {
        const glm::dvec3 c =
            (mesh.positions[t[0]] + mesh.positions[t[1]] + mesh.positions[t[2]]) / 3.0;
        const double d = relative_distance(*evaluator, c);
        a.centroid_max = std::max(a.centroid_max, d);
        a.centroid_mean += d;
    }
    if (!mesh.positions.empty()) a.vertex_mean /= double(mesh.positions.size());
    if (!mesh.triangles.empty()) a.centroid_mean /= double(mesh.triangles.size());
    return a;
}

void print_comparison() {
    std::printf(
        "\nsurface            octree ms  tris   evals/tri | uniform ms    n   tris   evals/tri | "
        "uniform/octree time\n");
    for (const Surface& s : kSurfaces) {
        const Measure& o = measures()["octree/" + std::string(s.name)];
        const Measure& u = measures()["uniform/" + std::string(s.name)];
        if (o.seconds == 0.0 || u.seconds == 0.0) continue;
        std::printf(
            "%-18s %9.2f %6zu %9.1f | %10.2f %4d %6zu %9.1f | %6.2f\n", s.name, 1e3 * o.seconds,
            o.triangles, o.triangles ? double(o.evaluations) / double(o.triangles) : 0.0,
            1e3 * u.seconds, u.cells_per_axis, u.triangles,
            u.triangles ? double(u.evaluations) / double(u.triangles) : 0.0, u.seconds / o.seconds);
    }
    std::printf(
        "\naccuracy, |f|/|grad f| over the box diagonal (vertices: max, mean; centroids: max, "
        "mean), and topology (components, Euler characteristic)\n"
        "surface            octree vertices     octree centroids   topo | uniform vertices    "
        "uniform centroids  topo | centroid mean uniform/octree\n");
    for (const Surface& s : kSurfaces) {
        const Measure& u = measures()["uniform/" + std::string(s.name)];
        if (u.cells_per_axis == 0) continue;
        const auto field = field_of(s.expression);
        const Mesh octree_mesh = octree(*field, 1).mesh;
        const Mesh uniform_mesh = uniform(*field, u.cells_per_axis);
        const Accuracy o = accuracy(*field, octree_mesh), g = accuracy(*field, uniform_mesh);
        const TopologyReport to = analyze_topology(octree_mesh),
                             tu = analyze_topology(uniform_mesh);
        std::printf(
            "%-18s %7.1e %7.1e   %7.1e %7.1e  %zu %3ld | %7.1e %7.1e   %7.1e %7.1e  %zu %3ld | "
            "%5.2f\n",
            s.name, o.vertex_max, o.vertex_mean, o.centroid_max, o.centroid_mean, to.components,
            to.euler_characteristic, g.vertex_max, g.vertex_mean, g.centroid_max, g.centroid_mean,
            tu.components, tu.euler_characteristic,
            o.centroid_mean > 0.0 ? g.centroid_mean / o.centroid_mean : 0.0);
    }
    const Measure& one = measures()["octree/thesis_sphere"];
    const Measure& all = measures()["octree_all_threads/thesis_sphere"];
    if (one.seconds > 0.0 && all.seconds > 0.0) {
        std::printf(
            "\nthesis sphere: %.2f ms on one thread (CPU), %.2f ms on all (wall); "
            "thesis: 9 ms; ratio one thread / thesis %.2f\n",
            1e3 * one.seconds, 1e3 * all.seconds, one.seconds / 9e-3);
    }
}

}  // namespace
}  // namespace isomesh

int main(int argc, char** argv) {
    using namespace isomesh;
    for (const Surface& s : kSurfaces) {
        benchmark::RegisterBenchmark((std::string("octree/") + s.name).c_str(), BM_octree, &s, 1)
            ->Unit(benchmark::kMillisecond);
        benchmark::RegisterBenchmark((std::string("uniform/") + s.name).c_str(), BM_uniform, &s)
            ->Unit(benchmark::kMillisecond);
    }
    benchmark::RegisterBenchmark("octree_all_threads/thesis_sphere", BM_octree, &kSurfaces[0], 0)
        ->Unit(benchmark::kMillisecond);
    benchmark::Initialize(&argc, argv);
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    print_comparison();
    return 0;
}
