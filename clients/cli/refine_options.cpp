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

RefineOutcome refine_first_mesh(std::shared_ptr<const Field> field, const Mesh& first,
                                const RefineOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    RefineSettings settings;
    settings.error_measure = make_error_measure(options.error_measure);
    settings.constraint = Constraint::budget_and_error_bound(
        options.triangles.value_or(kDefaultTriangleCap), options.max_error.value_or(0.0));
    if (options.triangles && first.triangles.size() > *options.triangles) {
        print_warning("phase 1 alone has " + std::to_string(first.triangles.size()) +
                      " triangles, more than --triangles " + std::to_string(*options.triangles) +
                      " (refinement only adds triangles to it; lower --depth MIN)");
    }
    Refiner refiner(std::move(field), first, std::move(settings));
    refiner.run_to_convergence();
    RefineOutcome outcome;
    outcome.mesh = refiner.mesh().mesh;
    const MeshStats stats = refiner.stats();
    outcome.error_total = stats.total_error;
    outcome.error_max = stats.max_error;
    outcome.splits = refiner.counters().splits;
    outcome.merges = refiner.counters().merges;
    outcome.time_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return outcome;
}

void add_refine_stats(nlohmann::ordered_json& stats, double first_mesh_ms,
                      const RefineOutcome& outcome) {
    stats["triangles"] = outcome.mesh.triangles.size();
    stats["vertices"] = outcome.mesh.positions.size();
    stats["first_mesh_ms"] = first_mesh_ms;
    stats["total_ms"] = first_mesh_ms + outcome.time_ms;
    stats["error_total"] = outcome.error_total;
    stats["error_max"] = outcome.error_max;
    stats["splits"] = outcome.splits;
    stats["merges"] = outcome.merges;
}

}  // namespace isomesh::cli
