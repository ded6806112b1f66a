// The progressive pipeline (progressive/pipeline.h: anytime phase 1 -> simplification to the
// triangle budget -> refinement) against a compiled uniform-grid baseline (grid_baseline.h:
// native sampling + flying-edges style Marching Cubes 33), in the same run, for the issue's
// gallery, the blobby cube and two CAD models. Per case:
// - first frame: the pipeline's first step with a 10 ms budget of thread CPU time (as the
//   server's first step): the CPU time it took, its triangles, and whether phase 1 was complete;
// - phase 1 complete (certified when every cell met the leaf conditions) and converged at 20,000
//   triangles: the whole pipeline on one thread, thread CPU time from the start, stepped in
//   2 ms slices as the server steps it until phase 1 is complete, then run to convergence;
// - phase 1 alone (polygonize() with the pipeline's phase-1 settings): thread CPU time on one
//   thread, and wall time on all threads (PolygonizeSettings::threads = 0);
// - the grid at the same triangle count as our converged mesh (n cells per axis, searched): its
//   time (sampling + meshing, thread CPU) and the ratio grid / ours;
// - equal accuracy: the area-weighted rms distance of our converged mesh to the surface
//   (MeshErrorReport::rms_distance: 10 points per triangle projected onto the surface; a mesh
//   with more than 20,000 triangles is measured on every k-th of them), then the coarsest grid
//   whose mesh has at most that rms distance (searched over n), its time and triangles, and the
//   ratio grid / ours: the target is >= 1 (our whole pipeline no slower than the grid);
// - bear.vm and colonnade.vm (phase 1 at depths 3..7 on [-1, 1]^3): phase 1 complete at depth 7
//   (target 0.5 s) beside the grid at 129^3 samples.
// The topology of each mesh (components, Euler characteristic) is printed beside it: a grid at
// equal rms distance may still miss small components (the blobby cube's bubbles).
//
// Timings are medians of up to three runs (fewer when a run takes over a second), on thread CPU
// time except the all-threads wall time; the machine is shared, so read the ratios, measured in
// the same run. The whole run takes a few minutes. Not part of the test command.
//
//   build/bin/bench_pipeline [case ...] [--runs N]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "bench_clock.h"
#include "eval/tape_field.h"
#include "expr/compile.h"
#include "expr/vm_reader.h"
#include "grid_baseline.h"
#include "mesh/topology.h"
#include "native_functions.h"
#include "polygonize/polygonizer.h"
#include "progressive/pipeline.h"
#include "refine/error_measures.h"

namespace isomesh {
namespace {

using bench::cpu_seconds;
using bench::NativeBatch;
using bench::wall_seconds;

constexpr std::size_t kBudget = 20'000;
constexpr std::int64_t kFirstFrameUs = 10'000;
constexpr std::int64_t kSliceUs = 2'000;  // the server's default slice (server/config.h)
constexpr int kSamplesPerEdge = 3;        // 10 samples per triangle
constexpr std::size_t kMeasuredTriangles = 20'000;
constexpr int kMaxCells = 800;        // the grid searches stop there
constexpr int kModelCells = 128;      // 129^3 samples, the numpy + VTK grid
constexpr double kModelTarget = 0.5;  // seconds to certified at depth 7

Box box_of(double x0, double x1, double y0, double y1, double z0, double z1) {
    return {{x0, y0, z0}, {x1, y1, z1}};
}
Box cube(double r) {
    return box_of(-r, r, -r, r, -r, r);
}

struct Case {
    const char* name;
    const char* source;  // an expression, or @model.vm from the shared test data
    Box box;
    NativeBatch native;
    bool model = false;  // phase 1 at depths 3..7, and the grid at 129^3 beside it
};

// The viewer's gallery surfaces (clients/web/src/gallery.js) and the others.
const Case kCases[] = {
    {"torus", "(sqrt(x^2+y^2)-2)^2+z^2=0.49", box_of(-3.2, 3.2, -3.2, 3.2, -1.2, 1.2),
     bench::native_torus},
    {"tanglecube", "x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8=0", cube(3), bench::native_tanglecube},
    {"gyroid", "sin(x)cos(y)+sin(y)cos(z)+sin(z)cos(x)=0", cube(6), bench::native_gyroid},
    {"heart", "(x^2+2.25y^2+z^2-1)^3-x^2z^3-0.1125y^2z^3=0", cube(1.5), bench::native_heart},
    {"genus_two", "((x^2+y^2)^2-x^2+y^2)^2+z^2=0.01", box_of(-1.4, 1.4, -0.9, 0.9, -0.3, 0.3),
     bench::native_genus_two},
    {"spheroid", "10x^2+y^2+z^2=20", cube(5), bench::native_spheroid},
    {"cosine_sphere", "x^2+y^2+z^2+2cos(2x)=10", cube(5), bench::native_cosine_sphere},
    {"thesis_sphere", "sqrt(x^2+y^2+z^2)=4.65", cube(5), bench::native_thesis_sphere},
    {"blobby_cube", "sqrt(x^2+y^2+z^2)+2cos(2x)+2cos(2y)+2cos(2z)=20", cube(28),
     bench::native_blobby_cube},
    {"bear", "@bear.vm", cube(1), native_bear, true},
    {"colonnade", "@colonnade.vm", cube(1), native_colonnade, true},
};

std::shared_ptr<const Field> field_of(const Case& c) {
    CompileResult result;
    if (c.source[0] == '@') {
        const std::string path = std::string(ISOMESH_SHARED_DIR "/testdata/vm/") + (c.source + 1);
        std::ifstream in(path);
        if (!in) throw std::runtime_error("cannot read " + path);
        std::stringstream text;
        text << in.rdbuf();
        result = read_vm(text.str());
    } else {
        result = compile_expression(c.source);
    }
    if (!result.ok()) throw std::runtime_error(c.name + (": " + result.error->to_string()));
    return make_tape_field(std::make_shared<const Tape>(std::move(result.tape)), {});
}

/// The native function computes the case's f: checked against the tape on random points.
void check_native(const Case& c, const Field& field) {
    constexpr std::size_t kPoints = 4096;
    std::mt19937 rng(7);
    std::vector<double> x(kPoints), y(kPoints), z(kPoints), tape(kPoints), native(kPoints);
    for (std::size_t i = 0; i < kPoints; ++i) {
        x[i] = std::uniform_real_distribution<double>(c.box.lo.x, c.box.hi.x)(rng);
        y[i] = std::uniform_real_distribution<double>(c.box.lo.y, c.box.hi.y)(rng);
        z[i] = std::uniform_real_distribution<double>(c.box.lo.z, c.box.hi.z)(rng);
    }
    field.make_evaluator()->values({x, y, z}, tape);
    c.native(x.data(), y.data(), z.data(), native.data(), kPoints);
    for (std::size_t i = 0; i < kPoints; ++i) {
        const double scale = std::max(1.0, std::abs(tape[i]));
        if (!(std::abs(tape[i] - native[i]) <= 1e-9 * scale) &&
            !(std::isnan(tape[i]) && std::isnan(native[i]))) {
            throw std::runtime_error(std::string(c.name) + ": the native function differs from " +
                                     "the tape at a point: " + std::to_string(native[i]) +
                                     " != " + std::to_string(tape[i]));
        }
    }
}

PipelineSettings pipeline_settings(const Case& c) {
    PipelineSettings s;
    s.phase1.box = c.box;
    s.phase1.threads = 1;
    if (c.model) {
        s.phase1.min_depth = 3;
        s.phase1.max_depth = 7;
    }
    s.refine.constraint = Constraint::triangle_budget(kBudget);
    return s;
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
}

/// Runs `run` (which returns its seconds) up to `runs` times, fewer when one takes over a
/// second; the median.
double timed(int runs, const std::function<double()>& run) {
    std::vector<double> seconds;
    double total = 0.0;
    for (int r = 0; r < runs && (r == 0 || total < 1.0); ++r) {
        seconds.push_back(run());
        total += seconds.back();
    }
    return median(seconds);
}

struct PipelineRun {
    double first = 0.0;  // seconds of thread CPU time from the start
    std::size_t first_triangles = 0;
    bool first_complete = false;
    double complete = 0.0;
    bool certified = false;
    std::size_t unresolved_cells = 0;
    double converged = 0.0;
    std::size_t triangles = 0;
    bool budget_unreachable = false;
    Mesh mesh;
};

PipelineRun run_pipeline(const Case& c, const std::shared_ptr<const Field>& field) {
    PipelineRun run;
    Pipeline pipeline(field, pipeline_settings(c));
    const double start = cpu_seconds();
    pipeline.step(WorkBudget(kFirstFrameUs, WorkBudget::thread_cpu_clock()));
    run.first = cpu_seconds() - start;
    run.first_triangles = pipeline.stats().triangles;
    run.first_complete = !pipeline.status().resolving;
    bool converged = false;
    while (pipeline.status().resolving)
        converged = pipeline.step(WorkBudget(kSliceUs, WorkBudget::thread_cpu_clock())).converged;
    run.complete = cpu_seconds() - start;
    run.certified = pipeline.status().certified;
    run.unresolved_cells = pipeline.status().unresolved_cells;
    if (!converged) pipeline.run_to_convergence();
    run.converged = cpu_seconds() - start;
    run.triangles = pipeline.stats().triangles;
    run.budget_unreachable = pipeline.status().budget_unreachable;
    run.mesh = pipeline.mesh().mesh;
    return run;
}

PipelineRun median_pipeline(const Case& c, const std::shared_ptr<const Field>& field, int runs) {
    std::vector<PipelineRun> all;
    double total = 0.0;
    for (int r = 0; r < runs && (r == 0 || total < 1.0); ++r) {
        all.push_back(run_pipeline(c, field));
        total += all.back().converged;
    }
    PipelineRun out = std::move(all.back());
    std::vector<double> first, complete, converged;
    for (const PipelineRun& r : all) {
        first.push_back(r.first);
        complete.push_back(r.complete);
        converged.push_back(r.converged);
    }
    out.first = median(first);
    out.complete = median(complete);
    out.converged = median(converged);
    return out;
}

struct Phase1Alone {
    double one_thread = 0.0;   // thread CPU seconds
    double all_threads = 0.0;  // wall seconds
    PolygonizeStats stats;
};

Phase1Alone phase1_alone(const Case& c, const Field& field, int runs) {
    Phase1Alone out;
    PolygonizeSettings settings = pipeline_settings(c).phase1;
    out.one_thread = timed(runs, [&] {
        const double start = cpu_seconds();
        out.stats = polygonize(field, settings).stats;
        return cpu_seconds() - start;
    });
    settings.threads = 0;
    out.all_threads = timed(runs, [&] {
        const double start = wall_seconds();
        polygonize(field, settings);
        return wall_seconds() - start;
    });
    return out;
}

/// The area-weighted rms distance to the surface, on at most kMeasuredTriangles triangles
/// (every k-th: the grid's triangles come slab by slab, so they spread over the whole surface).
double rms_distance(const Mesh& mesh, Evaluator& evaluator) {
    const std::size_t stride =
        (mesh.triangle_count() + kMeasuredTriangles - 1) / kMeasuredTriangles;
    if (stride <= 1) return measure_mesh_error(mesh, evaluator, kSamplesPerEdge).rms_distance;
    Mesh sample;
    sample.positions = mesh.positions;
    sample.normals = mesh.normals;
    for (std::size_t t = 0; t < mesh.triangle_count(); t += stride)
        sample.triangles.push_back(mesh.triangles[t]);
    return measure_mesh_error(sample, evaluator, kSamplesPerEdge).rms_distance;
}

struct GridRun {
    int cells = 0;
    std::size_t triangles = 0;
    double seconds = 0.0;  // sampling + meshing, thread CPU, median
    bench::GridTimes split;
    double rms = 0.0;
    TopologyReport topology;
};

/// The grid meshes of one case, each made once for its triangle count and rms distance.
class GridSearch {
  public:
    GridSearch(const Case& c, Evaluator& evaluator) : case_(c), evaluator_(evaluator) {}

    std::size_t triangles(int n) { return mesh(n).triangle_count(); }
    double rms(int n) {
        auto it = rms_.find(n);
        if (it != rms_.end()) return it->second;
        return rms_[n] = rms_distance(mesh(n), evaluator_);
    }

    /// The grid whose triangle count is closest to `target` (the count grows about as n^2).
    int equal_triangles(std::size_t target) {
        int n = 32;
        for (int step = 0; step < 6; ++step) {
            const double t = double(std::max<std::size_t>(triangles(n), 1));
            const int next =
                std::clamp(int(std::lround(n * std::sqrt(double(target) / t))), 2, kMaxCells);
            if (next == n) break;
            n = next;
        }
        const auto gap = [&](int m) { return std::abs(double(triangles(m)) - double(target)); };
        while (n > 2 && gap(n - 1) < gap(n)) --n;
        while (n < kMaxCells && gap(n + 1) < gap(n)) ++n;
        return n;
    }

    /// The coarsest grid whose rms distance is at most `target`, from a start at n (the rms
    /// distance falls about as n^-2: predicted, then bisected), or 0 if none up to kMaxCells.
    int equal_rms(double target, int n) {
        int fail = 1, pass = 0;  // the largest n known to fail, the smallest known to pass
        for (int tries = 0; tries < 12; ++tries) {
            const double r = rms(n);
            if (r <= target) {
                pass = pass == 0 ? n : std::min(pass, n);
            } else {
                fail = std::max(fail, n);
            }
            if (pass != 0 && pass - fail <= std::max(1, pass / 50)) return pass;
            const int predicted = int(std::ceil(n * std::sqrt(r / target)));
            if (pass == 0) {
                if (fail >= kMaxCells) return 0;
                n = std::min(kMaxCells, std::max(fail + 1, int(predicted * 1.03) + 1));
            } else if (fail <= 1 && predicted < pass && predicted > 2) {
                n = predicted;
            } else {
                n = (fail + pass) / 2;
            }
        }
        return pass;
    }

    GridRun timed_run(int n, int runs) {
        GridRun run;
        run.cells = n;
        run.triangles = triangles(n);
        run.rms = rms(n);
        run.topology = analyze_topology(mesh(n));
        run.seconds = timed(runs, [&] {
            const double start = cpu_seconds();
            const Mesh m = bench::grid_mesh(case_.native, case_.box, n);
            const double seconds = cpu_seconds() - start;
            if (m.triangle_count() != run.triangles) throw std::logic_error("grid not repeatable");
            return seconds;
        });
        bench::grid_mesh(case_.native, case_.box, n, &run.split);
        return run;
    }

  private:
    const Mesh& mesh(int n) {
        auto it = meshes_.find(n);
        if (it == meshes_.end())
            it = meshes_.emplace(n, bench::grid_mesh(case_.native, case_.box, n)).first;
        return it->second;
    }

    const Case& case_;
    Evaluator& evaluator_;
    std::map<int, Mesh> meshes_;
    std::map<int, double> rms_;
};

struct CaseResult {
    const Case* c = nullptr;
    PipelineRun ours;
    Phase1Alone phase1;
    double our_rms = 0.0;
    TopologyReport our_topology;
    GridRun equal_triangles;
    GridRun equal_rms;   // cells 0: no grid up to kMaxCells
    GridRun model_grid;  // models only
};

std::string topology_of(const TopologyReport& t) {
    return std::to_string(t.components) + " components, chi " +
           std::to_string(t.euler_characteristic);
}

std::string load_average() {
    std::ifstream in("/proc/loadavg");
    double a = 0, b = 0, c = 0;
    in >> a >> b >> c;
    char text[64];
    std::snprintf(text, sizeof text, "%.2f %.2f %.2f", a, b, c);
    return text;
}

CaseResult run_case(const Case& c, int runs) {
    CaseResult out;
    out.c = &c;
    const auto field = field_of(c);
    check_native(c, *field);
    auto evaluator = field->make_evaluator();
    std::printf("\n%s: %s on [%g,%g]x[%g,%g]x[%g,%g]%s\n", c.name, c.source, c.box.lo.x, c.box.hi.x,
                c.box.lo.y, c.box.hi.y, c.box.lo.z, c.box.hi.z,
                c.model ? ", phase 1 at depths 3..7" : "");

    out.ours = median_pipeline(c, field, runs);
    const PipelineRun& o = out.ours;
    std::printf("  first frame: %.2f ms CPU, %zu triangles, phase 1 %s\n", 1e3 * o.first,
                o.first_triangles, o.first_complete ? "complete" : "not complete");
    std::printf(
        "  pipeline, one thread: phase 1 complete at %.1f ms (%s, %zu unresolved cells), "
        "converged at %.1f ms with %zu triangles%s\n",
        1e3 * o.complete, o.certified ? "certified" : "not certified", o.unresolved_cells,
        1e3 * o.converged, o.triangles, o.budget_unreachable ? " (budget unreachable)" : "");
    out.phase1 = phase1_alone(c, *field, runs);
    std::printf(
        "  phase 1 alone: %.1f ms CPU on one thread, %.1f ms wall on all %u threads; %zu "
        "triangles, depth %d, %s\n",
        1e3 * out.phase1.one_thread, 1e3 * out.phase1.all_threads,
        std::thread::hardware_concurrency(), out.phase1.stats.triangles, out.phase1.stats.depth,
        out.phase1.stats.certified() ? "certified" : "not certified");

    out.our_rms = rms_distance(o.mesh, *evaluator);
    out.our_topology = analyze_topology(o.mesh);
    GridSearch grids(c, *evaluator);
    const int n_tri = grids.equal_triangles(o.triangles);
    out.equal_triangles = grids.timed_run(n_tri, runs);
    const GridRun& t = out.equal_triangles;
    std::printf(
        "  grid at equal triangles: %d^3 cells, %zu triangles, %.2f ms (sampling %.2f, meshing "
        "%.2f): grid / ours %.3f\n",
        t.cells, t.triangles, 1e3 * t.seconds, 1e3 * t.split.sampling, 1e3 * t.split.meshing,
        t.seconds / o.converged);
    std::printf("  rms distance to the surface: ours %.3e, grid at equal triangles %.3e (%.2fx)\n",
                out.our_rms, t.rms, t.rms / out.our_rms);
    const int n_rms = grids.equal_rms(out.our_rms, n_tri);
    if (n_rms > 0) {
        out.equal_rms = grids.timed_run(n_rms, runs);
        const GridRun& r = out.equal_rms;
        std::printf(
            "  grid at equal rms distance: %d^3 cells, %zu triangles, rms %.3e, %.2f ms "
            "(sampling %.2f, meshing %.2f): grid / ours %.3f (target >= 1)\n",
            r.cells, r.triangles, r.rms, 1e3 * r.seconds, 1e3 * r.split.sampling,
            1e3 * r.split.meshing, r.seconds / o.converged);
    } else {
        std::printf("  grid at equal rms distance: none up to %d^3 cells\n", kMaxCells);
    }
    std::printf("  topology: ours %s; grid at equal triangles %s; at equal rms %s\n",
                topology_of(out.our_topology).c_str(), topology_of(t.topology).c_str(),
                n_rms > 0 ? topology_of(out.equal_rms.topology).c_str() : "-");
    if (c.model) {
        out.model_grid = grids.timed_run(kModelCells, runs);
        const GridRun& m = out.model_grid;
        std::printf(
            "  depth 7: phase 1 complete at %.1f ms (target %.0f ms); grid at %d^3 samples: "
            "%.1f ms, %zu triangles, %s, rms %.3e: grid / ours %.3f\n",
            1e3 * o.complete, 1e3 * kModelTarget, kModelCells + 1, 1e3 * m.seconds, m.triangles,
            topology_of(m.topology).c_str(), m.rms, m.seconds / o.complete);
    }
    std::fflush(stdout);
    return out;
}

void print_throughput(const std::vector<CaseResult>& results) {
    std::printf(
        "\nGrid baseline throughput (thread CPU; at the equal-accuracy grid, or the "
        "equal-triangle one):\n  case            samples   Msamples/s sampling   Mcells/s "
        "meshing   Mcells/s total\n");
    for (const CaseResult& r : results) {
        const GridRun& g = r.equal_rms.cells > 0 ? r.equal_rms : r.equal_triangles;
        const double samples = std::pow(g.cells + 1.0, 3.0), cells = std::pow(g.cells, 3.0);
        std::printf("  %-14s %9.0f %13.1f %18.1f %16.1f\n", r.c->name, samples,
                    1e-6 * samples / g.split.sampling, 1e-6 * cells / g.split.meshing,
                    1e-6 * cells / g.seconds);
    }
}

void print_summary(const std::vector<CaseResult>& results, const std::string& load_before,
                   const std::string& command) {
    std::printf(
        "\nSummary (ms of thread CPU time, one thread; ratios grid / ours, measured in this run; "
        "load average %s before, %s after):\n",
        load_before.c_str(), load_average().c_str());
    std::printf(
        "  case          first frame (<= 10)   phase1 done  converged | grid = tris        "
        "ratio | rms ours  grid = rms          ratio (>= 1)\n");
    for (const CaseResult& r : results) {
        const PipelineRun& o = r.ours;
        const GridRun& t = r.equal_triangles;
        const GridRun& e = r.equal_rms;
        char rms_grid[64] = "none";
        char rms_ratio[32] = "-";
        if (e.cells > 0) {
            std::snprintf(rms_grid, sizeof rms_grid, "%4d^3 %8.1f", e.cells, 1e3 * e.seconds);
            std::snprintf(rms_ratio, sizeof rms_ratio, "%7.3f %s", e.seconds / o.converged,
                          e.seconds >= o.converged ? "ok" : "MISSED");
        }
        std::printf(
            "  %-13s %6.2f %6zu tris %s %9.1f %10.1f | %4d^3 %8.1f %7.3f | %8.2e  %-16s %s\n",
            r.c->name, 1e3 * o.first, o.first_triangles,
            o.first > 1e-3 * kFirstFrameUs * 1.05 ? "LATE" : (o.first_complete ? "done" : "    "),
            1e3 * o.complete, 1e3 * o.converged, t.cells, 1e3 * t.seconds, t.seconds / o.converged,
            r.our_rms, rms_grid, rms_ratio);
    }
    for (const CaseResult& r : results) {
        if (!r.c->model) continue;
        const GridRun& m = r.model_grid;
        std::printf(
            "  %-13s depth 7: phase 1 done at %.1f ms (target %.0f: %s) vs grid %d^3 %.1f ms: "
            "grid / ours %.3f\n",
            r.c->name, 1e3 * r.ours.complete, 1e3 * kModelTarget,
            r.ours.complete <= kModelTarget ? "ok" : "MISSED", kModelCells + 1, 1e3 * m.seconds,
            m.seconds / r.ours.complete);
    }
    std::printf(
        "  (first frame: its triangles, \"done\" when phase 1 was complete, LATE over 10 ms; "
        "phase1 "
        "done: the pipeline's phase 1 complete, stepped in %lld ms slices)\n",
        static_cast<long long>(kSliceUs / 1000));
    std::printf("\nReproduce: %s\n", command.c_str());
}

}  // namespace
}  // namespace isomesh

int main(int argc, char** argv) {
    using namespace isomesh;
    int runs = 3;
    std::vector<std::string> names;
    std::string command = "build/bin/bench_pipeline";
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--help" || arg == "-h") {
            std::printf("usage: bench_pipeline [case ...] [--runs N]\ncases:");
            for (const Case& c : kCases) std::printf(" %s", c.name);
            std::printf("\n");
            return 0;
        }
        command += " " + arg;
        if (arg == "--runs" && i + 1 < argc) {
            runs = std::max(1, std::atoi(argv[++i]));
            command += std::string(" ") + argv[i];
        } else {
            names.push_back(arg);
        }
    }
    const std::string load_before = load_average();
    std::printf("bench_pipeline: budget %zu triangles, first frame %lld ms, load average %s\n",
                kBudget, static_cast<long long>(kFirstFrameUs / 1000), load_before.c_str());
    // Tables built at first use (Marching Cubes 33's) are built before anything is timed, as
    // in a server that has meshed once.
    bench::grid_mesh(bench::native_torus, cube(3), 8);
    std::vector<CaseResult> results;
    try {
        for (const Case& c : kCases) {
            if (!names.empty() && std::find(names.begin(), names.end(), c.name) == names.end())
                continue;
            results.push_back(run_case(c, runs));
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_pipeline: %s\n", e.what());
        return 1;
    }
    print_throughput(results);
    print_summary(results, load_before, command);
    return 0;
}
