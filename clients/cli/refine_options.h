// The refinement part of `isomesh mesh`: --triangles, --max-error and --error-measure run phase 2
// (refine/refiner.h) on the phase-1 mesh.
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "args.h"
#include "eval/evaluator.h"
#include "mesh/mesh.h"

namespace isomesh::cli {

inline constexpr OptionSpec kRefineOptionSpecs[] = {
    {"triangles", true, false}, {"max-error", true, false}, {"error-measure", true, false}};

/// The triangle budget of --max-error without --triangles (also the server's default maximum).
inline constexpr std::size_t kDefaultTriangleCap = 2'000'000;

inline constexpr std::string_view kRefineUsage =
    R"(  --triangles N       refine (phase 2) to N triangles: met within 1 and never exceeded,
                      unless phase 1 alone has more (then lower --depth MIN)
  --max-error E       refine until no triangle's error exceeds E (with --triangles as a
                      cap, else at most 2,000,000 triangles)
  --error-measure M   distance (default), epsilon4 or max_distance
                      (with --triangles or --max-error, --depth defaults to 3,9)
)";

struct RefineOptions {
    std::optional<std::size_t> triangles;
    std::optional<double> max_error;
    std::string error_measure = "distance";
    bool refine() const { return triangles || max_error; }
};

/// Reads the refinement options; throws UsageError for bad values or an unknown measure.
RefineOptions parse_refine_options(const Arguments& args);

struct RefineOutcome {
    Mesh mesh;
    double time_ms = 0.0;
    double error_total = 0.0;
    double error_max = 0.0;
    std::size_t splits = 0;
    std::size_t merges = 0;
};

/// Refines `first` (phase 1's mesh of `field`) to the constraint the options describe.
RefineOutcome refine_first_mesh(std::shared_ptr<const Field> field, const Mesh& first,
                                const RefineOptions& options);

/// Updates --stats output for a refined mesh: triangles and vertices of the output, and
/// first_mesh_ms (phase 1), total_ms, error_total, error_max, splits, merges.
void add_refine_stats(nlohmann::ordered_json& stats, double first_mesh_ms,
                      const RefineOutcome& outcome);

}  // namespace isomesh::cli
