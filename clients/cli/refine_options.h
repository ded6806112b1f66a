// The refinement part of `isomesh mesh`: --triangles, --max-error and --error-measure run the
// progressive pipeline (progressive/pipeline.h: phase 1, simplification to the budget where
// phase 1's mesh is larger, refinement) to convergence, as the server does.
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "args.h"
#include "eval/evaluator.h"
#include "mesh/mesh.h"
#include "polygonize/polygonizer.h"
#include "progressive/pipeline.h"

namespace isomesh::cli {

inline constexpr OptionSpec kRefineOptionSpecs[] = {
    {"triangles", true, false}, {"max-error", true, false}, {"error-measure", true, false}};

/// The triangle budget of --max-error without --triangles (also the server's default maximum).
inline constexpr std::size_t kDefaultTriangleCap = 2'000'000;

inline constexpr std::string_view kRefineUsage =
    R"(  --triangles N       refine (phase 2) to N triangles: met within 1 and never exceeded
                      (phase 1's mesh, if it has more, is simplified to N/4 first where its
                      topology allows, else to N, and split back to N by error; where
                      that topology needs more than N triangles, the result is
                      the smallest mesh found, and --stats says budget_unreachable)
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
    double first_mesh_ms = 0.0;  ///< the pipeline's first step (within kFirstMeshBudgetUs)
    double total_ms = 0.0;
    double error_total = 0.0;
    double error_max = 0.0;
    std::size_t splits = 0;
    std::size_t merges = 0;
    PipelineStatus status;
    PolygonizeStats phase1;  ///< of the last phase-1 mesh
};

/// The CPU time of the first step, as the server's default (microseconds).
inline constexpr std::int64_t kFirstMeshBudgetUs = 10'000;

/// Runs the pipeline on `field` with `phase1`'s box, depths and threads to the constraint the
/// options describe.
RefineOutcome refine(std::shared_ptr<const Field> field, const PolygonizeSettings& phase1,
                     const RefineOptions& options);

/// --stats output of a refined mesh: triangles and vertices of the output, first_mesh_ms,
/// total_ms, error_total, error_max, splits, merges, and phase 1's certification (certified,
/// unresolved_cells, phase1_meshes, budget_unreachable).
nlohmann::ordered_json refine_stats(const RefineOutcome& outcome);

}  // namespace isomesh::cli
