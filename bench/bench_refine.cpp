// Progressive refinement speed, single-threaded (one refiner per worker):
// - refine/<surface>/<measure>: splits per second (counter splits_per_s, per second of the thread's
//   CPU time), projection, error and the delta included, from the phase-1 mesh to 40,000
//   triangles. Ratio printed: epsilon4 against the default "distance".
// - refine_fresh/<surface>/distance: the same with no recycled memory (refine/array_memory.h), as
//   a server's first sessions, or many new ones at once: every array on fresh pages, zeroed by
//   the kernel. Ratio printed: recycled / fresh time.
//
// Memory as in isomesh-server: glibc maps every allocation over 256 kB anew
// (server/resources.cpp), so arrays the refiner does not recycle itself come fresh from the
// kernel, as in a session. Without it glibc's heap would hand later iterations the pages of
// earlier ones. ISOMESH_BENCH_MALLOC=default keeps glibc's defaults.
// - queue/<kind>: the same refinement with the bucket queue and with the binary heap, and
//   queue_ops/<kind>: the queues alone on a ROAM-like trace (pop the top, push two children with a
//   fraction of its priority, remove one other element). Ratio printed: heap time / bucket time.
// - change/<surface>: a parameter change re-converged at 20,000 triangles: the refiner alone
//   (set_field, vertices moved, no topology check) and the whole pipeline (progressive/pipeline.h:
//   phase 1 of the new function runs again and decides whether the moved mesh keeps the new
//   topology), against meshing the new function from scratch with the pipeline (phase 1 +
//   refinement to the same budget). Ratio printed: change / scratch (aim: below 1/3).
#include <benchmark/benchmark.h>
#include <malloc.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <map>
#include <memory>
#include <random>
#include <string>

#include "eval/tape_field.h"
#include "expr/compile.h"
#include "expr/parameters.h"
#include "polygonize/polygonizer.h"
#include "progressive/pipeline.h"
#include "refine/array_memory.h"
#include "refine/refiner.h"

namespace isomesh {
namespace {

// Thread CPU time: the machine is shared, and wall-clock time counts other processes' turns.
double cpu_seconds() {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

struct Surface {
    const char* name;
    const char* expression;  // with a parameter a
    double a;
    double a_changed;
};

const Surface kSurfaces[] = {
    {"sphere", "x^2+y^2+z^2=a", 4.0, 4.2},
    {"cosine_sphere", "x^2+y^2+z^2+2cos(2x)=a", 5.0, 5.2},
    {"torus", "(sqrt(x^2+y^2)-2)^2+z^2=a", 0.64, 0.7},
};

std::shared_ptr<const Field> field_of(const Surface& s, double a) {
    static std::map<std::string, std::shared_ptr<const Tape>> tapes;
    auto& tape = tapes[s.expression];
    if (!tape) tape = std::make_shared<const Tape>(compile_expression(s.expression).tape);
    return make_tape_field(tape, bind_parameters(*tape, {{"a", a}}).values);
}

Mesh phase1(const Field& field) {
    PolygonizeSettings settings;
    settings.min_depth = 3;
    settings.threads = 1;
    return polygonize(field, settings).mesh;
}

RefineSettings settings_for(std::size_t triangles, const char* measure, QueueKind queue) {
    RefineSettings s;
    s.constraint = Constraint::triangle_budget(triangles);
    s.error_measure = make_error_measure(measure);
    s.queue = queue;
    return s;
}

PipelineSettings pipeline_settings(std::size_t triangles) {
    PipelineSettings s;
    s.refine = settings_for(triangles, "distance", QueueKind::Bucket);
    return s;
}

// Seconds per iteration of each benchmark, for the ratios printed at the end.
std::map<std::string, double>& seconds() {
    static std::map<std::string, double> s;
    return s;
}

double elapsed(double start) {
    return cpu_seconds() - start;
}

void refine_to(benchmark::State& state, const Surface& surface, const char* measure,
               QueueKind queue, const std::string& key) {
    auto field = field_of(surface, surface.a);
    const Mesh first = phase1(*field);
    double total = 0.0;
    std::size_t splits = 0;
    for (auto _ : state) {
        const double start = cpu_seconds();
        Refiner refiner(field, first, settings_for(40000, measure, queue));
        refiner.run_to_convergence();
        total += elapsed(start);
        splits += refiner.counters().splits;
    }
    state.counters["splits_per_s"] =
        benchmark::Counter(double(splits), benchmark::Counter::kIsRate);
    seconds()[key] = total / double(state.iterations());
}

void BM_Refine(benchmark::State& state, const Surface* surface, const char* measure) {
    refine_to(state, *surface, measure, QueueKind::Bucket,
              std::string("refine/") + surface->name + "/" + measure);
}

void BM_RefineFresh(benchmark::State& state, const Surface* surface) {
    set_recycled_memory_limit(0);
    refine_to(state, *surface, "distance", QueueKind::Bucket,
              std::string("refine_fresh/") + surface->name + "/distance");
    set_recycled_memory_limit(kDefaultRecycledMemoryBytes);
}

void BM_QueueRefine(benchmark::State& state, QueueKind kind) {
    refine_to(state, kSurfaces[1], "distance", kind,
              kind == QueueKind::Bucket ? "queue/bucket" : "queue/heap");
}

void BM_QueueOps(benchmark::State& state, QueueKind kind) {
    // A ROAM-like trace on 100,000 elements with priorities spread over 12 orders of magnitude.
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::unique_ptr<PriorityQueue> queue;
    if (kind == QueueKind::Bucket)
        queue = std::make_unique<BucketQueue>(QueueOrder::HighestFirst);
    else
        queue = std::make_unique<HeapQueue>(QueueOrder::HighestFirst);
    std::uint32_t next = 0;
    for (; next < 100000; ++next) queue->insert(next, std::pow(10.0, -12.0 * unit(rng)));
    std::size_t operations = 0;
    double total = 0.0;
    for (auto _ : state) {
        const double start = cpu_seconds();
        for (int i = 0; i < 10000; ++i) {
            const std::uint32_t top = queue->top();
            const double p = queue->priority(top);
            queue->remove(top);
            queue->insert(next++, p * (0.05 + 0.25 * unit(rng)));
            queue->insert(next++, p * (0.05 + 0.25 * unit(rng)));
            const std::uint32_t other = next - 3 - static_cast<std::uint32_t>(unit(rng) * 1000);
            if (queue->contains(other)) queue->remove(other);
            operations += 5;
        }
        total += elapsed(start);
    }
    state.counters["ops_per_s"] =
        benchmark::Counter(double(operations), benchmark::Counter::kIsRate);
    seconds()[kind == QueueKind::Bucket ? "queue_ops/bucket" : "queue_ops/heap"] =
        total / double(state.iterations());
}

/// Re-converges `mesher` (a Refiner or a Pipeline) after each parameter change.
template <class Mesher>
void time_changes(benchmark::State& state, const Surface* surface, Mesher& mesher,
                  const std::string& key) {
    mesher.run_to_convergence();
    double total = 0.0;
    bool changed = false;
    for (auto _ : state) {
        changed = !changed;
        auto field = field_of(*surface, changed ? surface->a_changed : surface->a);
        const double start = cpu_seconds();
        mesher.set_field(field);
        mesher.run_to_convergence();
        total += elapsed(start);
    }
    state.counters["restarts"] = double(mesher.counters().restarts);
    seconds()[key] = total / double(state.iterations());
}

void BM_Change(benchmark::State& state, const Surface* surface, bool topology_check) {
    auto first = field_of(*surface, surface->a);
    const std::string key =
        std::string("change/") + surface->name + (topology_check ? "/checked" : "/unchecked");
    if (topology_check) {
        Pipeline pipeline(first, pipeline_settings(20000));
        time_changes(state, surface, pipeline, key);
    } else {
        Refiner refiner(first, phase1(*first), settings_for(20000, "distance", QueueKind::Bucket));
        time_changes(state, surface, refiner, key);
    }
}

void BM_Scratch(benchmark::State& state, const Surface* surface) {
    auto field = field_of(*surface, surface->a_changed);
    double total = 0.0;
    for (auto _ : state) {
        const double start = cpu_seconds();
        Pipeline pipeline(field, pipeline_settings(20000));
        pipeline.run_to_convergence();
        total += elapsed(start);
    }
    seconds()[std::string("scratch/") + surface->name] = total / double(state.iterations());
}

void register_all() {
    for (const Surface& s : kSurfaces) {
        for (const char* measure : {"distance", "epsilon4"})
            benchmark::RegisterBenchmark((std::string("refine/") + s.name + "/" + measure).c_str(),
                                         BM_Refine, &s, measure)
                ->Unit(benchmark::kMillisecond);
        benchmark::RegisterBenchmark((std::string("refine_fresh/") + s.name + "/distance").c_str(),
                                     BM_RefineFresh, &s)
            ->Unit(benchmark::kMillisecond);
    }
    benchmark::RegisterBenchmark("queue/bucket", BM_QueueRefine, QueueKind::Bucket)
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark("queue/heap", BM_QueueRefine, QueueKind::Heap)
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark("queue_ops/bucket", BM_QueueOps, QueueKind::Bucket)
        ->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark("queue_ops/heap", BM_QueueOps, QueueKind::Heap)
        ->Unit(benchmark::kMicrosecond);
    for (const Surface& s : kSurfaces) {
        benchmark::RegisterBenchmark((std::string("scratch/") + s.name).c_str(), BM_Scratch, &s)
            ->Unit(benchmark::kMillisecond);
        benchmark::RegisterBenchmark((std::string("change/") + s.name + "/unchecked").c_str(),
                                     BM_Change, &s, false)
            ->Unit(benchmark::kMillisecond);
        benchmark::RegisterBenchmark((std::string("change/") + s.name + "/checked").c_str(),
                                     BM_Change, &s, true)
            ->Unit(benchmark::kMillisecond);
    }
}

void print_ratio(const char* what, const std::string& a, const std::string& b) {
    const auto& s = seconds();
    if (!s.contains(a) || !s.contains(b) || s.at(b) <= 0.0) return;
    std::printf("  %-48s %8.3f  (%s / %s)\n", what, s.at(a) / s.at(b), a.c_str(), b.c_str());
}

void print_ratios() {
    std::printf("\nRatios (same run):\n");
    for (const Surface& s : kSurfaces) {
        const std::string n = s.name;
        print_ratio(("epsilon4 time / distance time, " + n).c_str(), "refine/" + n + "/epsilon4",
                    "refine/" + n + "/distance");
        print_ratio(("recycled / fresh memory time, " + n).c_str(), "refine/" + n + "/distance",
                    "refine_fresh/" + n + "/distance");
    }
    print_ratio("heap / bucket, whole refinement", "queue/heap", "queue/bucket");
    print_ratio("heap / bucket, queue operations alone", "queue_ops/heap", "queue_ops/bucket");
    for (const Surface& s : kSurfaces) {
        const std::string n = s.name;
        print_ratio(("change / scratch, no topology check, " + n).c_str(),
                    "change/" + n + "/unchecked", "scratch/" + n);
        print_ratio(("change / scratch, phase-1 topology check, " + n).c_str(),
                    "change/" + n + "/checked", "scratch/" + n);
    }
}

}  // namespace
}  // namespace isomesh

int main(int argc, char** argv) {
    const char* malloc_mode = std::getenv("ISOMESH_BENCH_MALLOC");
    if (!malloc_mode || std::string(malloc_mode) != "default")
        mallopt(M_MMAP_THRESHOLD, 256 * 1024);
    benchmark::Initialize(&argc, argv);
    isomesh::register_all();
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    isomesh::print_ratios();
    return 0;
}
