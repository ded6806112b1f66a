// Batch evaluation speed: the tape evaluator against the same functions compiled natively, on a
// 1024 x 1024 grid over [-1, 1]^2 at z = 0 (one slice of the 3D models).
//
// Baselines, measured in the same run:
// - native_<model>: the function as C++. The sphere, the thesis's function and tanglecube are
//   written by hand below; bear and prospero are translated from their .vm files to straight-line
//   C++ at build time (bench/vm_to_cpp.cmake, into the build tree). Every native loop is compiled
//   with the evaluator's own flags (-O3 -fno-math-errno -fno-trapping-math) and AVX2 clones
//   (ISOMESH_VECTOR_CLONES), so GCC vectorizes it as it does the evaluator's loops: the comparison
//   is with the best the compiler does, not with scalar code.
// - tape/<model> reports ratio_vs_native = tape time / native time (the goal: below 2).
// - tiled/prospero evaluates the same grid in 64 x 64 tiles, each inside push(tile)/pop(), with
//   tape simplification on and off: speedup_vs_unsimplified is the gain from simplification.
// - per_instruction/<model>/<kind>: the cost of one evaluation of each kind (value, value_gradient,
//   interval, interval_gradient; single and batched by 8 as the octree batches a cell's children)
//   per tape instruction, at points and on boxes spread over the model's box (boxes 1/32 of it
//   across, an octree cell at depth 5), with the kernels (ns_per_instruction) and with the
//   reference evaluation (TapeFieldOptions::reference: the evaluator before the kernels, one
//   instruction at a time, same results bit for bit): speedup_vs_reference. For single values,
//   ratio_vs_native compares with the native function called on one point.
// - octree_step/<model>: what the octree does per cell: interval_gradients of a cell's 8 children,
//   then push(child)/pop() for each (tape simplification from the choices just recorded), per
//   child, kernels against the reference.
#include <benchmark/benchmark.h>

#include <cmath>
#include <ctime>
#include <fstream>
#include <map>
#include <memory>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "eval/batch_kernels.h"
#include "eval/tape_field.h"
#include "expr/compile.h"
#include "expr/vm_reader.h"

// Generated from the .vm files at build time.
void native_bear(const double* x, const double* y, const double* z, double* out, std::size_t n);
void native_prospero(const double* x, const double* y, const double* z, double* out, std::size_t n);
void native_colonnade(const double* x, const double* y, const double* z, double* out,
                      std::size_t n);

namespace isomesh {
namespace {

constexpr int kResolution = 1024;
constexpr int kTile = 64;
constexpr std::size_t kPoints = std::size_t{kResolution} * kResolution;

using NativeBatch = void (*)(const double*, const double*, const double*, double*, std::size_t);

ISOMESH_VECTOR_CLONES void native_sphere(const double* x, const double* y, const double* z,
                                         double* out, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) out[i] = x[i] * x[i] + y[i] * y[i] + z[i] * z[i] - 1.0;
}

ISOMESH_VECTOR_CLONES void native_thesis(const double* x, const double* y, const double* z,
                                         double* out, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
        out[i] = std::sqrt(x[i] * x[i] + y[i] * y[i] + z[i] * z[i]) + 2 * std::cos(2 * x[i]) +
                 2 * std::cos(2 * y[i]) + 2 * std::cos(2 * z[i]) - 20;
    }
}

ISOMESH_VECTOR_CLONES void native_tanglecube(const double* x, const double* y, const double* z,
                                             double* out, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
        double x2 = x[i] * x[i], y2 = y[i] * y[i], z2 = z[i] * z[i];
        out[i] = x2 * x2 - 5 * x2 + y2 * y2 - 5 * y2 + z2 * z2 - 5 * z2 + 10;
    }
}

struct Model {
    const char* name;
    std::string source;  // an expression, or @file.vm
    NativeBatch native;
    double scale = 1.0;  // the model's box is [-scale, scale]^3
};

const std::vector<Model>& models() {
    static const std::vector<Model> all = {
        {"sphere", "x^2+y^2+z^2-1", native_sphere},
        {"thesis", "sqrt(x^2+y^2+z^2)+2cos(2x)+2cos(2y)+2cos(2z)-20", native_thesis, 28.0},
        {"tanglecube", "@tanglecube.vm", native_tanglecube, 3.0},
        {"bear", "@bear.vm", native_bear},
        {"colonnade", "@colonnade.vm", native_colonnade},
        {"prospero", "@prospero.vm", native_prospero},
    };
    return all;
}

const Model& model(const std::string& name) {
    for (const Model& m : models())
        if (name == m.name) return m;
    throw std::invalid_argument("no model " + name);
}

std::shared_ptr<const Tape> compile(const std::string& source) {
    CompileResult result;
    if (source[0] == '@') {
        std::ifstream in(ISOMESH_SHARED_DIR "/testdata/vm/" + source.substr(1));
        std::stringstream text;
        text << in.rdbuf();
        result = read_vm(text.str());
    } else {
        result = compile_expression(source);
    }
    if (!result.ok()) throw std::runtime_error(source + ": " + result.error->to_string());
    return std::make_shared<const Tape>(std::move(result.tape));
}

/// The grid's points in structure-of-arrays form, row by row or tile by tile.
struct Points {
    std::vector<double> x, y, z;
    PointBatch batch(std::size_t first, std::size_t count) const {
        return {{x.data() + first, count}, {y.data() + first, count}, {z.data() + first, count}};
    }
};

double coordinate(int i) {
    return -1.0 + 2.0 * i / (kResolution - 1);
}

const Points& grid_rows() {
    static const Points points = [] {
        Points p;
        for (int j = 0; j < kResolution; ++j)
            for (int i = 0; i < kResolution; ++i)
                p.x.push_back(coordinate(i)), p.y.push_back(coordinate(j)), p.z.push_back(0.0);
        return p;
    }();
    return points;
}

const Points& grid_tiles() {
    static const Points points = [] {
        Points p;
        for (int tj = 0; tj < kResolution; tj += kTile)
            for (int ti = 0; ti < kResolution; ti += kTile)
                for (int j = tj; j < tj + kTile; ++j)
                    for (int i = ti; i < ti + kTile; ++i)
                        p.x.push_back(coordinate(i)), p.y.push_back(coordinate(j)),
                            p.z.push_back(0.0);
        return p;
    }();
    return points;
}

/// Mean seconds per evaluation of the whole grid, by benchmark kind and model, for the ratios.
std::map<std::string, double>& timings() {
    static std::map<std::string, double> t;
    return t;
}

/// CPU time of the calling thread: the machine is shared, and wall time would count the time other
/// processes hold the core.
double thread_seconds() {
    timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

/// Runs `evaluate` once per iteration, timing it by hand so the mean can feed other ratios.
template <class F>
double timed_loop(benchmark::State& state, const F& evaluate) {
    double total = 0.0;
    for (auto _ : state) {
        double start = thread_seconds();
        evaluate();
        double seconds = thread_seconds() - start;
        state.SetIterationTime(seconds);
        total += seconds;
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * kPoints));
    return total / static_cast<double>(state.iterations());
}

/// Mean seconds of `key`, measured now if its benchmark did not run (filtered out).
template <class F>
double timing(const std::string& key, const F& evaluate) {
    auto it = timings().find(key);
    if (it != timings().end()) return it->second;
    evaluate();  // warm up
    double start = thread_seconds();
    const int runs = 3;
    for (int r = 0; r < runs; ++r) evaluate();
    return timings()[key] = (thread_seconds() - start) / runs;
}

void run_native(const Model& m, std::vector<double>& out) {
    const Points& p = grid_rows();
    m.native(p.x.data(), p.y.data(), p.z.data(), out.data(), kPoints);
    benchmark::DoNotOptimize(out.data());
}

void BM_native(benchmark::State& state, const char* name) {
    const Model& m = model(name);
    std::vector<double> out(kPoints);
    timings()[std::string("native/") + name] = timed_loop(state, [&] { run_native(m, out); });
}

void BM_tape(benchmark::State& state, const char* name) {
    const Model& m = model(name);
    auto evaluator = make_tape_field(compile(m.source), {})->make_evaluator();
    const Points& p = grid_rows();
    std::vector<double> out(kPoints), native(kPoints);
    double seconds = timed_loop(state, [&] {
        evaluator->values(p.batch(0, kPoints), out);
        benchmark::DoNotOptimize(out.data());
    });
    timings()[std::string("tape/") + name] = seconds;
    double native_seconds = timing(std::string("native/") + name, [&] { run_native(m, native); });
    run_native(m, native);
    double difference = 0.0;  // the two compute the same function
    for (std::size_t i = 0; i < kPoints; ++i)
        difference = std::max(difference, std::fabs(out[i] - native[i]));
    state.counters["ratio_vs_native"] = seconds / native_seconds;
    state.counters["max_difference"] = difference;
    state.counters["instructions"] = static_cast<double>(active_tape_size(*evaluator));
}

/// The grid in 64 x 64 tiles, each evaluated inside push(tile)/pop().
void BM_tiled(benchmark::State& state, const char* name) {
    const Model& m = model(name);
    const bool simplify = state.range(0) != 0;
    auto evaluator =
        make_tape_field(compile(m.source), {}, {.simplify = simplify})->make_evaluator();
    const Points& p = grid_tiles();
    std::vector<double> out(kPoints);
    const std::size_t tile_points = kTile * kTile;
    std::size_t instructions = 0;
    double seconds = timed_loop(state, [&] {
        instructions = 0;
        for (std::size_t first = 0; first < kPoints; first += tile_points) {
            Box tile{{p.x[first], p.y[first], 0.0},
                     {p.x[first + tile_points - 1], p.y[first + tile_points - 1], 0.0}};
            evaluator->push(tile);
            instructions += active_tape_size(*evaluator);
            evaluator->values(p.batch(first, tile_points), {out.data() + first, tile_points});
            evaluator->pop();
        }
        benchmark::DoNotOptimize(out.data());
    });
    std::string key = std::string("tiled/") + name + (simplify ? "/on" : "/off");
    timings()[key] = seconds;
    std::vector<double> native(kPoints);
    state.counters["ratio_vs_native"] =
        seconds / timing(std::string("native/") + name, [&] { run_native(m, native); });
    state.counters["mean_tile_instructions"] =
        static_cast<double>(instructions) / static_cast<double>(kPoints / tile_points);
    if (simplify) {
        auto plain = make_tape_field(compile(m.source), {}, {.simplify = false})->make_evaluator();
        double unsimplified = timing(std::string("tiled/") + name + "/off", [&] {
            for (std::size_t first = 0; first < kPoints; first += tile_points)
                plain->values(p.batch(first, tile_points), {out.data() + first, tile_points});
        });
        state.counters["speedup_vs_unsimplified"] = unsimplified / seconds;
    }
}

/// Points and boxes spread over a model's box by a fixed generator, for per_instruction.
struct Samples {
    std::vector<double> x, y, z;
    std::vector<Box> boxes;
};

constexpr std::size_t kSamples = 1024;

Samples samples(const Model& m) {
    Samples s;
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(-m.scale, m.scale);
    const double cell = 2.0 * m.scale / 32;
    for (std::size_t i = 0; i < kSamples; ++i) {
        const glm::dvec3 p(u(rng), u(rng), u(rng));
        s.x.push_back(p.x), s.y.push_back(p.y), s.z.push_back(p.z);
        s.boxes.push_back({p, p + cell});
    }
    return s;
}

enum class Kind {
    Value,
    Values8,
    ValueGradient,
    ValueGradients8,
    Interval,
    Intervals8,
    IntervalGradient,
    IntervalGradients8,
};

const char* kind_name(Kind k) {
    switch (k) {
        case Kind::Value:
            return "value";
        case Kind::Values8:
            return "values_by_8";
        case Kind::ValueGradient:
            return "value_gradient";
        case Kind::ValueGradients8:
            return "value_gradients_by_8";
        case Kind::Interval:
            return "interval";
        case Kind::Intervals8:
            return "intervals_by_8";
        case Kind::IntervalGradient:
            return "interval_gradient";
        case Kind::IntervalGradients8:
            return "interval_gradients_by_8";
    }
    return "";
}

/// Evaluates every sample once in the way `kind` says; returns a checksum.
double evaluate_samples(Evaluator& e, const Samples& s, Kind kind) {
    double sum = 0.0;
    std::vector<double> values(8);
    std::vector<ValueGradient> gradients(8);
    std::vector<IntervalValue> intervals(8);
    std::vector<IntervalGradient> interval_gradients(8);
    auto batch = [&](std::size_t i) {
        return PointBatch{{s.x.data() + i, 8}, {s.y.data() + i, 8}, {s.z.data() + i, 8}};
    };
    for (std::size_t i = 0; i < kSamples; i += 8) {
        switch (kind) {
            case Kind::Value:
                for (std::size_t j = i; j < i + 8; ++j) sum += e.value({s.x[j], s.y[j], s.z[j]});
                break;
            case Kind::Values8:
                e.values(batch(i), values);
                sum += values[0];
                break;
            case Kind::ValueGradient:
                for (std::size_t j = i; j < i + 8; ++j)
                    sum += e.value_gradient({s.x[j], s.y[j], s.z[j]}).gradient.x;
                break;
            case Kind::ValueGradients8:
                e.value_gradients(batch(i), gradients);
                sum += gradients[0].gradient.x;
                break;
            case Kind::Interval:
                for (std::size_t j = i; j < i + 8; ++j) sum += e.interval(s.boxes[j]).value.lo;
                break;
            case Kind::Intervals8:
                e.intervals({s.boxes.data() + i, 8}, intervals);
                sum += intervals[0].value.lo;
                break;
            case Kind::IntervalGradient:
                for (std::size_t j = i; j < i + 8; ++j)
                    sum += e.interval_gradient(s.boxes[j]).gradient[0].lo;
                break;
            case Kind::IntervalGradients8:
                e.interval_gradients({s.boxes.data() + i, 8}, interval_gradients);
                sum += interval_gradients[0].gradient[0].lo;
                break;
        }
    }
    return sum;
}

/// Mean seconds of `evaluate` over a few runs after a warm-up, for the baselines.
template <class F>
double seconds_of(const F& evaluate) {
    evaluate();
    const int runs = 3;
    double start = thread_seconds();
    for (int r = 0; r < runs; ++r) evaluate();
    return (thread_seconds() - start) / runs;
}

void BM_per_instruction(benchmark::State& state, const char* name, Kind kind) {
    const Model& m = model(name);
    auto tape = compile(m.source);
    auto kernels = make_tape_field(tape, {}, {.simplify = false})->make_evaluator();
    auto reference =
        make_tape_field(tape, {}, {.simplify = false, .reference = true})->make_evaluator();
    const Samples s = samples(m);
    double total = 0.0;
    for (auto _ : state) {
        double start = thread_seconds();
        benchmark::DoNotOptimize(evaluate_samples(*kernels, s, kind));
        double seconds = thread_seconds() - start;
        state.SetIterationTime(seconds);
        total += seconds;
    }
    const double instructions = static_cast<double>(active_tape_size(*kernels));
    const double per_eval = total / static_cast<double>(state.iterations() * kSamples);
    const double reference_per_eval =
        seconds_of([&] { benchmark::DoNotOptimize(evaluate_samples(*reference, s, kind)); }) /
        kSamples;
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * kSamples));
    state.counters["instructions"] = instructions;
    state.counters["ns_per_instruction"] = 1e9 * per_eval / instructions;
    state.counters["reference_ns_per_instruction"] = 1e9 * reference_per_eval / instructions;
    state.counters["speedup_vs_reference"] = reference_per_eval / per_eval;
    if (kind == Kind::Value) {
        std::vector<double> out(1);
        const double native_per_eval = seconds_of([&] {
                                           for (std::size_t i = 0; i < kSamples; ++i)
                                               m.native(&s.x[i], &s.y[i], &s.z[i], out.data(), 1);
                                           benchmark::DoNotOptimize(out.data());
                                       }) /
                                       kSamples;
        state.counters["ratio_vs_native"] = per_eval / native_per_eval;
    }
}

/// Per child of a cell: interval_gradients of the 8 children, then push(child)/pop() of each.
double octree_steps(Evaluator& e, const Samples& s) {
    std::vector<IntervalGradient> out(8);
    double sum = 0.0;
    for (std::size_t i = 0; i < kSamples; i += 8) {
        const Box& parent = s.boxes[i];
        std::vector<Box> children(8);
        const glm::dvec3 half = 0.5 * parent.size();
        for (int c = 0; c < 8; ++c) {
            glm::dvec3 lo = parent.lo + glm::dvec3(c & 1, (c >> 1) & 1, (c >> 2) & 1) * half;
            children[c] = {lo, lo + half};
        }
        e.interval_gradients(children, out);
        for (const Box& child : children) {
            e.push(child);
            sum += static_cast<double>(active_tape_size(e));
            e.pop();
        }
    }
    return sum;
}

void BM_octree_step(benchmark::State& state, const char* name) {
    const Model& m = model(name);
    auto tape = compile(m.source);
    auto kernels = make_tape_field(tape, {})->make_evaluator();
    auto reference = make_tape_field(tape, {}, {.reference = true})->make_evaluator();
    const Samples s = samples(m);
    double total = 0.0;
    for (auto _ : state) {
        double start = thread_seconds();
        benchmark::DoNotOptimize(octree_steps(*kernels, s));
        double seconds = thread_seconds() - start;
        state.SetIterationTime(seconds);
        total += seconds;
    }
    const double per_child = total / static_cast<double>(state.iterations() * kSamples);
    const double reference_per_child =
        seconds_of([&] { benchmark::DoNotOptimize(octree_steps(*reference, s)); }) / kSamples;
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * kSamples));
    state.counters["us_per_child"] = 1e6 * per_child;
    state.counters["speedup_vs_reference"] = reference_per_child / per_child;
}

void register_benchmarks() {
    for (const Model& m : models()) {
        benchmark::RegisterBenchmark((std::string("native/") + m.name).c_str(), BM_native, m.name)
            ->UseManualTime()
            ->Unit(benchmark::kMillisecond);
        benchmark::RegisterBenchmark((std::string("tape/") + m.name).c_str(), BM_tape, m.name)
            ->UseManualTime()
            ->Unit(benchmark::kMillisecond);
    }
    for (const char* name : {"bear", "colonnade", "thesis", "tanglecube", "prospero"}) {
        for (Kind kind :
             {Kind::Value, Kind::Values8, Kind::ValueGradient, Kind::ValueGradients8,
              Kind::Interval, Kind::Intervals8, Kind::IntervalGradient, Kind::IntervalGradients8}) {
            benchmark::RegisterBenchmark(
                (std::string("per_instruction/") + name + "/" + kind_name(kind)).c_str(),
                BM_per_instruction, name, kind)
                ->UseManualTime()
                ->MinTime(0.2)
                ->Unit(benchmark::kMicrosecond);
        }
        benchmark::RegisterBenchmark((std::string("octree_step/") + name).c_str(), BM_octree_step,
                                     name)
            ->UseManualTime()
            ->MinTime(0.2)
            ->Unit(benchmark::kMicrosecond);
    }
    benchmark::RegisterBenchmark("tiled/prospero", BM_tiled, "prospero")
        ->ArgName("simplify")
        ->Arg(0)
        ->Arg(1)
        ->UseManualTime()
        ->Unit(benchmark::kMillisecond);
}

}  // namespace
}  // namespace isomesh

int main(int argc, char** argv) {
    isomesh::register_benchmarks();
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
