#include "refine_options.h"

#include <chrono>
#include <cmath>

#include "output.h"
#include "refine/refiner.h"

namespace isomesh::cli {

RefineOptions parse_refine_options(const Arguments& args) {
    RefineOptions options;
    if (args.has("triangles")) {
        const double n = parse_number(*args.value("triangles"), "--triangles");
        if (n != std::floor(n) || n < 1 || n > 1e9)
            throw UsageError("--triangles: expected a whole number from 1 to 1000000000");
        options.triangles = static_cast<std::size_t>(n);
    }
    if (args.has("max-error")) {
        const double e = parse_number(*args.value("max-error"), "--max-error");
        if (!(e > 0.0)) throw UsageError("--max-error: expected a positive number");
        options.max_error = e;
    }
    if (args.has("error-measure")) {
        options.error_measure = std::string(*args.value("error-measure"));
        if (!make_error_measure(options.error_measure)) {
            std::string names;
            for (const std::string& name : error_measure_names())
                names += (names.empty() ? "" : ", ") + name;
            throw UsageError("--error-measure: unknown measure '" + options.error_measure +
                             "' (one of " + names + ")");
        }
    }
    if (args.has("error-measure") && !options.refine())
        throw UsageError("--error-measure needs --triangles or --max-error");
    return options;
}

RefineOutcome refine(std::shared_ptr<const Field> field, const PolygonizeSettings& phase1,
                     const RefineOptions& options) {
    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    auto ms_since_start = [&] {
        return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    };
    PipelineSettings settings;
    settings.phase1 = phase1;
    settings.refine.error_measure = make_error_measure(options.error_measure);
    settings.refine.constraint = Constraint::budget_and_error_bound(
        options.triangles.value_or(kDefaultTriangleCap), options.max_error.value_or(0.0));
    Pipeline pipeline(std::move(field), std::move(settings));
    RefineOutcome outcome;
    const PipelineStep first =
        pipeline.step(WorkBudget(kFirstMeshBudgetUs, WorkBudget::thread_cpu_clock()));
    outcome.first_mesh_ms = ms_since_start();
    if (!first.converged) pipeline.run_to_convergence();
    outcome.total_ms = ms_since_start();
    outcome.mesh = pipeline.mesh().mesh;
    const MeshStats stats = pipeline.stats();
    outcome.error_total = stats.total_error;
    outcome.error_max = stats.max_error;
    outcome.splits = pipeline.counters().splits;
    outcome.merges = pipeline.counters().merges;
    outcome.status = pipeline.status();
    outcome.phase1 = pipeline.phase1_stats();
    return outcome;
}

nlohmann::ordered_json refine_stats(const RefineOutcome& outcome) {
    nlohmann::ordered_json stats;
    stats["triangles"] = outcome.mesh.triangles.size();
    stats["vertices"] = outcome.mesh.positions.size();
    stats["first_mesh_ms"] = outcome.first_mesh_ms;
    stats["total_ms"] = outcome.total_ms;
    stats["error_total"] = outcome.error_total;
    stats["error_max"] = outcome.error_max;
    stats["splits"] = outcome.splits;
    stats["merges"] = outcome.merges;
    stats["certified"] = outcome.status.certified;
    stats["unresolved_cells"] = outcome.status.unresolved_cells;
    stats["phase1_meshes"] = outcome.status.phase1_meshes;
    stats["phase1_triangles"] = outcome.phase1.triangles;
    stats["phase1_cells"] = outcome.phase1.cells;
    stats["budget_unreachable"] = outcome.status.budget_unreachable;
    return stats;
}

}  // namespace isomesh::cli
