// The progressive pipeline (progressive/pipeline.h: anytime phase 1 -> simplification to the
// triangle budget -> refinement), started as the server starts it, against meshing the same
// function on a uniform grid with compiled sampling, in the same run, for the surfaces
// (issue 9): the gallery, the spheroid, x^2+y^2+z^2+2cos(2x)=10, the blobby cube and two CAD
// models. The peers (each samples f natively: native_functions.h, vm_to_cpp.cmake):
// - vtk: VTK's vtkFlyingEdges3D (vtk_baseline.h), built when CMake finds VTK (libvtk9-dev);
// - grid: our own flying-edges style Marching Cubes 33 (grid_baseline.h), always built.
// Per case:
// - first frame: the pipeline's first step with a 10 ms budget of thread CPU time (the server's
//   first step): the CPU time it took, its triangles, and whether phase 1 was complete;
// - phase 1 complete (certified when every cell met the leaf conditions) and converged at 20,000
//   triangles: the whole pipeline on one thread, thread CPU time from the start, stepped in 2 ms
//   slices as the server steps it until phase 1 is complete (the longest of those steps is
//   printed: an anytime phase 1 returns within about a slice), then run to convergence. As the
//   server does after its eval_timeout (10 s), phase 1 is settled (Pipeline::settle) after 10 s
//   of CPU time, unless --full or --phase1-limit 0: a settled case's times are lower bounds;
// - equal accuracy: the area-weighted rms distance of our converged mesh to the surface
//   (MeshErrorReport::rms_distance: 10 points per triangle projected onto the surface; a mesh
//   with more than 20,000 triangles is measured on every k-th of them), then, per peer, the
//   coarsest grid whose mesh has at most that rms distance (searched over n cells per axis), its
//   time (sampling + meshing, thread CPU) and triangles, and the ratio ours / peer: the issue's
//   target is <= 1 (our whole pipeline no slower than the compiled grid);
// - per peer, the grid at the same triangle count as our converged mesh, its rms and time;
// - bear.vm and colonnade.vm (phase 1 at depths 3..7 on [-1, 1]^3): phase 1 complete at depth 7
//   (target 0.5 s) beside each peer at 129^3 samples (the numpy + VTK grid), and the
//   pipeline once more with phase 1 on every core, in wall time (a lone session on an idle
//   server, whose workers help its phase 1);
// - with --full, phase 1 alone (polygonize() with the pipeline's phase-1 settings) on one thread
//   and on all, and the thesis's sphere |r| = 4.65 with phase 1's default settings beside the
//   thesis's 9 ms for about 2,000 triangles.
// The topology of each mesh (components, Euler characteristic) is printed beside it: a grid at
// equal rms distance may still miss small components (the blobby cube's bubbles).
//
// Timings are thread CPU time (the peers are made to run on one thread, as the pipeline does),
// medians of --runs runs (1 by default, 3 with --full; fewer when a run takes over a second); the
// machine is shared, so read the ratios, measured in the same run, and the load average printed.
// The default run takes 5-10 minutes on two loaded cores, most of it the pipeline's own time on
// the blobby cube and the models. Not part of the test command.
//
//   build/bin/bench_pipeline [case ...] [--full] [--runs N] [--phase1-limit S] [--peer vtk|grid]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <optional>
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
#include "grid_search.h"
#include "mesh/topology.h"
#include "native_functions.h"
#include "polygonize/polygonizer.h"
#include "progressive/pipeline.h"
#include "refine/error_measures.h"

#ifdef ISOMESH_BENCH_VTK
#include "vtk_baseline.h"
#endif

namespace isomesh {
namespace {

using bench::cpu_seconds;
using bench::GridRun;
using bench::GridSearch;
using bench::GridTimes;
using bench::median;
using bench::NativeBatch;
using bench::Peer;
using bench::rms_distance;
using bench::timed;
using bench::wall_seconds;

constexpr std::size_t kBudget = 20'000;
constexpr std::int64_t kFirstFrameUs = 10'000;
constexpr std::int64_t kSliceUs = 2'000;     // the server's default slice (server/config.h)
constexpr int kModelCells = 128;             // 129^3 samples, the numpy + VTK grid
constexpr double kModelTarget = 0.5;         // seconds to certified at depth 7
constexpr double kServerPhase1Limit = 10.0;  // the server's eval_timeout_ms, in seconds

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
    bool model = false;   // phase 1 at depths 3..7, and the grids at 129^3 beside it
    bool full = false;    // run with --full only
    double thesis = 0.0;  // the thesis's phase-1 time (seconds) at the default settings
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
    {"blobby_cube", "sqrt(x^2+y^2+z^2)+2cos(2x)+2cos(2y)+2cos(2z)=20", cube(28),
     bench::native_blobby_cube},
    {"bear", "@bear.vm", cube(1), native_bear, true},
    {"colonnade", "@colonnade.vm", cube(1), native_colonnade, true},
    {"thesis_sphere", "sqrt(x^2+y^2+z^2)=4.65", cube(5), bench::native_thesis_sphere, false, true,
     9e-3},
};

const Peer kPeers[] = {
#ifdef ISOMESH_BENCH_VTK
    {"vtk", bench::vtk_flying_edges_mesh, 512},
#endif
    {"grid", bench::grid_mesh, 800},
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

/// As the server's MeshSession::restart sets the pipeline up (one thread, the default phase-1
/// depths and error measure), with the depths for the models.
PipelineSettings pipeline_settings(const Case& c, int threads = 1) {
    PipelineSettings s;
    s.phase1.box = c.box;
    s.phase1.threads = threads;
    if (c.model) {
        s.phase1.min_depth = 3;
        s.phase1.max_depth = 7;
    }
    s.refine.constraint = Constraint::triangle_budget(kBudget);
    return s;
}

struct Options {
    int runs = 1;
    bool full = false;
    /// Thread CPU seconds of phase 1 after which the pipeline settles it (Pipeline::settle), as
    /// the server does after its eval_timeout (server/config.h); 0: no limit.
    double phase1_limit = kServerPhase1Limit;
    std::vector<std::string> cases;  // empty: every case of the run
    std::vector<std::string> peers;  // empty: every peer built
};

struct PipelineRun {
    double first = 0.0;  // seconds of thread CPU time from the start
    std::size_t first_triangles = 0;
    bool first_complete = false;
    double complete = 0.0;
    bool certified = false;
    std::size_t unresolved_cells = 0;
    bool settled = false;  // phase 1 stopped at the limit (Options::phase1_limit)
    /// The steps after the first until phase 1 was complete, and the longest (each has a budget
    /// of kSliceUs: an anytime phase 1 returns within about that).
    std::size_t steps = 0;
    double longest_step = 0.0;
    double converged = 0.0;
    std::size_t triangles = 0;
    bool budget_unreachable = false;
    Mesh mesh;
};

/// The pipeline stepped as the server steps it: `threads` for phase 1 (1, or 0 for every core, as
/// an idle server lends its workers to a lone session), times read from `now` (thread CPU time on
/// one thread, wall time on all; the steps' budgets are the calling thread's CPU time either way).
PipelineRun run_pipeline(const Case& c, const std::shared_ptr<const Field>& field,
                         double phase1_limit, int threads = 1, double (*now)() = &cpu_seconds) {
    PipelineRun run;
    Pipeline pipeline(field, pipeline_settings(c, threads));
    const double start = now();
    pipeline.step(WorkBudget(kFirstFrameUs, WorkBudget::thread_cpu_clock()));
    run.first = now() - start;
    run.first_triangles = pipeline.stats().triangles;
    run.first_complete = !pipeline.status().resolving;
    bool converged = false;
    while (pipeline.status().resolving) {
        const double step_start = now();
        if (phase1_limit > 0.0 && !run.settled && step_start - start >= phase1_limit) {
            pipeline.settle();
            run.settled = true;
        }
        converged = pipeline.step(WorkBudget(kSliceUs, WorkBudget::thread_cpu_clock())).converged;
        run.longest_step = std::max(run.longest_step, now() - step_start);
        ++run.steps;
    }
    run.complete = now() - start;
    run.certified = pipeline.status().certified;
    run.unresolved_cells = pipeline.status().unresolved_cells;
    if (!converged) pipeline.run_to_convergence();
    run.converged = now() - start;
    run.triangles = pipeline.stats().triangles;
    run.budget_unreachable = pipeline.status().budget_unreachable;
    run.mesh = pipeline.mesh().mesh;
    return run;
}

PipelineRun median_pipeline(const Case& c, const std::shared_ptr<const Field>& field,
                            const Options& options) {
    std::vector<PipelineRun> all;
    double total = 0.0;
    for (int r = 0; r < options.runs && (r == 0 || total < 1.0); ++r) {
        all.push_back(run_pipeline(c, field, options.phase1_limit));
        total += all.back().converged;
    }
    PipelineRun out = std::move(all.back());
    std::vector<double> first, complete, converged, longest_step;
    for (const PipelineRun& r : all) {
        first.push_back(r.first);
        complete.push_back(r.complete);
        converged.push_back(r.converged);
        longest_step.push_back(r.longest_step);
    }
    out.first = median(first);
    out.complete = median(complete);
    out.converged = median(converged);
    out.longest_step = median(longest_step);
    return out;
}

/// Phase 1 alone, as polygonize() runs it with `settings`: thread CPU time on one thread, wall
/// time on all, and the one-thread run's statistics.
struct Phase1Alone {
    double one_thread = 0.0;
    double all_threads = 0.0;
    PolygonizeStats stats;
};

Phase1Alone phase1_alone(const Field& field, PolygonizeSettings settings, int runs) {
    Phase1Alone out;
    settings.threads = 1;
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

void print_phase1_alone(const char* what, const Phase1Alone& p) {
    std::printf(
        "  %s: %.1f ms CPU on one thread, %.1f ms wall on all %u threads; %zu triangles, depth "
        "%d, %s\n",
        what, 1e3 * p.one_thread, 1e3 * p.all_threads, std::thread::hardware_concurrency(),
        p.stats.triangles, p.stats.depth, p.stats.certified() ? "certified" : "not certified");
}

struct PeerResult {
    const Peer* peer = nullptr;
    GridRun equal_triangles;
    GridRun equal_rms;
    GridRun model_grid;  // models only
};

struct CaseResult {
    const Case* c = nullptr;
    PipelineRun ours;
    /// Models only: the pipeline with phase 1 on every core (wall time), as a lone session on an
    /// idle server runs it.
    std::optional<PipelineRun> ours_all_threads;
    double our_rms = 0.0;
    TopologyReport our_topology;
    std::vector<PeerResult> peers;
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

void print_ours(const PipelineRun& o) {
    std::printf("  first frame: %.2f ms CPU, %zu triangles, phase 1 %s\n", 1e3 * o.first,
                o.first_triangles, o.first_complete ? "complete" : "not complete");
    std::printf(
        "  pipeline, one thread: phase 1 complete at %.1f ms (%s%s, %zu unresolved cells), "
        "converged at %.1f ms with %zu triangles%s\n",
        1e3 * o.complete, o.settled ? "settled at the limit, " : "",
        o.certified ? "certified" : "not certified", o.unresolved_cells, 1e3 * o.converged,
        o.triangles, o.budget_unreachable ? " (budget unreachable)" : "");
    std::printf("  phase 1 after the first frame: %zu steps of %lld ms, the longest %.1f ms\n",
                o.steps, static_cast<long long>(kSliceUs / 1000), 1e3 * o.longest_step);
}

PeerResult run_peer(const Case& c, const Peer& peer, const CaseResult& ours, Evaluator& evaluator,
                    int runs) {
    PeerResult out;
    out.peer = &peer;
    const double converged = ours.ours.converged;
    GridSearch grids(c.native, c.box, peer, evaluator);
    const int n_tri = grids.equal_triangles(ours.ours.triangles);
    out.equal_triangles = grids.timed_run(n_tri, runs);
    const GridRun& t = out.equal_triangles;
    std::printf(
        "  %s at equal triangles: %d^3 cells, %zu triangles, rms %.3e (ours %.3e), %.2f ms "
        "(sampling %.2f, meshing %.2f): ours / %s %.2f; %s\n",
        peer.name, t.cells, t.triangles, t.rms, ours.our_rms, 1e3 * t.seconds,
        1e3 * t.split.sampling, 1e3 * t.split.meshing, peer.name, converged / t.seconds,
        topology_of(t.topology).c_str());
    const int n_rms = grids.equal_rms(ours.our_rms, n_tri);
    if (n_rms > 0) {
        out.equal_rms = grids.timed_run(n_rms, runs);
        const GridRun& r = out.equal_rms;
        std::printf(
            "  %s at equal rms distance: %d^3 cells, %zu triangles, rms %.3e, %.2f ms (sampling "
            "%.2f, meshing %.2f): ours / %s %.2f (target <= 1); %s\n",
            peer.name, r.cells, r.triangles, r.rms, 1e3 * r.seconds, 1e3 * r.split.sampling,
            1e3 * r.split.meshing, peer.name, converged / r.seconds,
            topology_of(r.topology).c_str());
    } else {
        std::printf("  %s at equal rms distance: none up to %d^3 cells\n", peer.name,
                    peer.max_cells);
    }
    if (c.model) {
        out.model_grid = grids.timed_run(kModelCells, runs);
        const GridRun& m = out.model_grid;
        std::printf(
            "  %s at %d^3 samples: %.1f ms, %zu triangles, rms %.3e, %s: ours (phase 1 "
            "complete) / %s %.2f\n",
            peer.name, kModelCells + 1, 1e3 * m.seconds, m.triangles, m.rms,
            topology_of(m.topology).c_str(), peer.name, ours.ours.complete / m.seconds);
    }
    std::fflush(stdout);
    return out;
}

CaseResult run_case(const Case& c, const Options& options) {
    CaseResult out;
    out.c = &c;
    const auto field = field_of(c);
    check_native(c, *field);
    auto evaluator = field->make_evaluator();
    std::printf("\n%s: %s on [%g,%g]x[%g,%g]x[%g,%g]%s\n", c.name, c.source, c.box.lo.x, c.box.hi.x,
                c.box.lo.y, c.box.hi.y, c.box.lo.z, c.box.hi.z,
                c.model ? ", phase 1 at depths 3..7" : "");
    out.ours = median_pipeline(c, field, options);
    print_ours(out.ours);
    if (c.model) {
        out.ours_all_threads = run_pipeline(c, field, options.phase1_limit, 0, &wall_seconds);
        std::printf(
            "  pipeline, all %u threads (wall): phase 1 complete at %.1f ms, converged at %.1f "
            "ms\n",
            std::thread::hardware_concurrency(), 1e3 * out.ours_all_threads->complete,
            1e3 * out.ours_all_threads->converged);
    }
    if (options.full) {
        print_phase1_alone("phase 1 alone",
                           phase1_alone(*field, pipeline_settings(c).phase1, options.runs));
    }
    if (c.thesis > 0.0) {
        PolygonizeSettings defaults;
        defaults.box = c.box;
        const Phase1Alone p = phase1_alone(*field, defaults, options.runs);
        print_phase1_alone("phase 1 at its default settings", p);
        std::printf(
            "  thesis: %.0f ms for about 2,000 triangles; ours (one thread) / thesis %.2f\n",
            1e3 * c.thesis, p.one_thread / c.thesis);
    }
    out.our_rms = rms_distance(out.ours.mesh, *evaluator);
    out.our_topology = analyze_topology(out.ours.mesh);
    std::printf("  ours: rms distance %.3e, %s\n", out.our_rms,
                topology_of(out.our_topology).c_str());
    std::fflush(stdout);
    for (const Peer& peer : kPeers) {
        if (!options.peers.empty() &&
            std::find(options.peers.begin(), options.peers.end(), peer.name) == options.peers.end())
            continue;
        out.peers.push_back(run_peer(c, peer, out, *evaluator, options.runs));
    }
    return out;
}

void print_throughput(const std::vector<CaseResult>& results) {
    std::printf(
        "\nPeers' throughput (thread CPU; at the equal-rms grid, or the equal-triangle one):\n"
        "  case           peer   samples   Msamples/s sampling   Mcells/s meshing   Mcells/s "
        "total\n");
    for (const CaseResult& r : results) {
        for (const PeerResult& p : r.peers) {
            const GridRun& g = p.equal_rms.cells > 0 ? p.equal_rms : p.equal_triangles;
            const double samples = std::pow(g.cells + 1.0, 3.0), cells = std::pow(g.cells, 3.0);
            std::printf("  %-14s %-5s %9.0f %13.1f %18.1f %16.1f\n", r.c->name, p.peer->name,
                        samples, 1e-6 * samples / g.split.sampling, 1e-6 * cells / g.split.meshing,
                        1e-6 * cells / g.seconds);
        }
    }
}

void print_summary(const std::vector<CaseResult>& results, const Options& options,
                   const std::string& load_before, const std::string& command) {
    std::printf(
        "\nSummary: ms of thread CPU time on one thread, the pipeline at a budget of %zu "
        "triangles; each peer at the coarsest grid with at most our rms distance (n^3 cells), "
        "ratio ours (converged) / peer (target <= 1); load average %s before, %s after\n",
        kBudget, load_before.c_str(), load_average().c_str());
    std::printf("  %-13s %8s %6s %9s %8s %10s %6s %9s", "case", "first", "tris", "phase1",
                "step max", "converged", "tris", "rms");
    for (const PeerResult& p : results.empty() ? std::vector<PeerResult>{} : results[0].peers)
        std::printf(" | %-4s %5s %8s %6s", p.peer->name, "n", "ms", "ratio");
    std::printf("\n");
    for (const CaseResult& r : results) {
        const PipelineRun& o = r.ours;
        std::printf("  %-13s %8.2f %6zu %9.1f %8.1f %10.1f %6zu %9.2e", r.c->name, 1e3 * o.first,
                    o.first_triangles, 1e3 * o.complete, 1e3 * o.longest_step, 1e3 * o.converged,
                    o.triangles, r.our_rms);
        for (const PeerResult& p : r.peers) {
            const GridRun& e = p.equal_rms;
            if (e.cells > 0) {
                std::printf(" | %-4s %5d %8.1f %6.2f", p.peer->name, e.cells, 1e3 * e.seconds,
                            o.converged / e.seconds);
            } else {
                std::printf(" | %-4s %5s %8s %6s", p.peer->name, "none", "-", "-");
            }
        }
        std::printf("%s%s%s\n", o.first > 1e-6 * kFirstFrameUs * 1.05 ? "  first frame LATE" : "",
                    o.settled ? "  settled" : "", o.certified ? "" : "  not certified");
    }
    for (const CaseResult& r : results) {
        if (!r.c->model) continue;
        const double all = r.ours_all_threads->complete;
        std::printf(
            "  %-13s depth 7: phase 1 complete at %.1f ms CPU on one thread, %.1f ms wall on all "
            "%u (target %.0f: %s)",
            r.c->name, 1e3 * r.ours.complete, 1e3 * all, std::thread::hardware_concurrency(),
            1e3 * kModelTarget,
            r.ours.complete <= kModelTarget ? "met"
            : all <= kModelTarget           ? "met on all threads"
                                            : "MISSED");
        for (const PeerResult& p : r.peers) {
            std::printf("; %s at %d^3 samples %.1f ms, ours / %s %.2f", p.peer->name,
                        kModelCells + 1, 1e3 * p.model_grid.seconds, p.peer->name,
                        r.ours.complete / p.model_grid.seconds);
        }
        std::printf("\n");
    }
    std::printf(
        "  (first: the first step's ms and triangles, budget %lld ms; phase1: the pipeline's "
        "phase 1 complete, stepped in %lld ms slices; step max: the longest of those steps; rms: "
        "area-weighted distance to the "
        "surface; settled: phase 1 stopped after %g s as the server stops it, so the times are "
        "lower bounds of the time to the certified mesh)\n",
        static_cast<long long>(kFirstFrameUs / 1000), static_cast<long long>(kSliceUs / 1000),
        options.phase1_limit);
    std::printf("\nReproduce: %s\n", command.c_str());
}

void print_usage() {
    std::printf(
        "usage: bench_pipeline [case ...] [--full] [--runs N] [--phase1-limit S] [--peer NAME]...\n"
        "  --full            every case, phase 1 alone too, 3 runs each, phase 1 unlimited\n"
        "                    (default: the issue's cases, 1 run, phase 1 settled after %g s)\n"
        "  --runs N          timed runs per measurement (the median is printed)\n"
        "  --phase1-limit S  settle phase 1 after S s of CPU time as the server does (0: never)\n"
        "  --peer NAME       only this peer (repeatable)\ncases:",
        kServerPhase1Limit);
    for (const Case& c : kCases) std::printf(" %s%s", c.name, c.full ? " (--full)" : "");
    std::printf("\npeers:");
    for (const Peer& p : kPeers) std::printf(" %s", p.name);
    std::printf("\n");
}

/// Parses the command line; false when the program is to exit (after --help or an error).
bool parse(int argc, char** argv, Options& options, std::string& command, int& status) {
    bool runs_given = false, limit_given = false;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        command += " " + arg;
        const bool has_value = i + 1 < argc;
        if (arg == "--help" || arg == "-h") {
            print_usage();
            status = 0;
            return false;
        } else if (arg == "--full") {
            options.full = true;
        } else if (arg == "--runs" && has_value) {
            options.runs = std::max(1, std::atoi(argv[++i]));
            runs_given = true;
            command += std::string(" ") + argv[i];
        } else if (arg == "--phase1-limit" && has_value) {
            options.phase1_limit = std::max(0.0, std::atof(argv[++i]));
            limit_given = true;
            command += std::string(" ") + argv[i];
        } else if (arg == "--peer" && has_value) {
            options.peers.push_back(argv[++i]);
            command += std::string(" ") + argv[i];
        } else if (arg.starts_with("-")) {
            std::fprintf(stderr, "bench_pipeline: unknown option %s (--help)\n", arg.c_str());
            status = 2;
            return false;
        } else {
            options.cases.push_back(arg);
        }
    }
    const auto unknown = [&](const std::string& name, const std::string& kind) {
        std::fprintf(stderr, "bench_pipeline: no %s %s (--help)\n", kind.c_str(), name.c_str());
        status = 2;
        return false;
    };
    for (const std::string& name : options.cases) {
        if (std::none_of(std::begin(kCases), std::end(kCases),
                         [&](const Case& c) { return name == c.name; }))
            return unknown(name, "case");
    }
    for (const std::string& name : options.peers) {
        if (std::none_of(std::begin(kPeers), std::end(kPeers),
                         [&](const Peer& p) { return name == p.name; }))
            return unknown(name, "peer");
    }
    if (options.full && !runs_given) options.runs = 3;
    if (options.full && !limit_given) options.phase1_limit = 0.0;
    return true;
}

bool selected(const Case& c, const Options& options) {
    if (options.cases.empty()) return options.full || !c.full;
    return std::find(options.cases.begin(), options.cases.end(), c.name) != options.cases.end();
}

}  // namespace
}  // namespace isomesh

int main(int argc, char** argv) {
    using namespace isomesh;
    Options options;
    std::string command = "build/bin/bench_pipeline";
    int status = 0;
    if (!parse(argc, argv, options, command, status)) return status;
    const std::string load_before = load_average();
    std::printf(
        "bench_pipeline: budget %zu triangles, first frame %lld ms, %d run(s), phase 1 limit %g s "
        "(0: none), load average %s\n",
        kBudget, static_cast<long long>(kFirstFrameUs / 1000), options.runs, options.phase1_limit,
        load_before.c_str());
    std::vector<CaseResult> results;
    try {
        // Tables built at first use (Marching Cubes 33's, VTK's) are built before anything is
        // timed, as in a server that has meshed once.
        for (const Peer& peer : kPeers) peer.mesh(bench::native_torus, cube(3), 8, nullptr);
        for (const Case& c : kCases) {
            if (selected(c, options)) results.push_back(run_case(c, options));
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_pipeline: %s\n", e.what());
        return 1;
    }
    print_throughput(results);
    print_summary(results, options, load_before, command);
    return 0;
}
