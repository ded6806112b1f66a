// `isomesh mesh`: phase 1 polygonization of a function (or a sampled .iso grid) to a glTF (.glb),
// STL, PLY or OBJ file, with optional statistics as one JSON line.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "args.h"
#include "commands.h"
#include "eval/grid_field.h"
#include "function_input.h"
#include "mesh_export.h"
#include "output.h"
#include "polygonize/polygonizer.h"
#include "refine/refiner.h"
#include "refine_options.h"
#include "server_mesh.h"

namespace isomesh::cli {

namespace {

constexpr std::string_view kUsage =
    R"(usage: isomesh mesh EXPR -o FILE [--param NAME=VALUE]... [--box x0,x1,y0,y1,z0,z1]
                    [--depth MIN,MAX] [--threads N] [--stats]
                    [--triangles N] [--max-error E] [--error-measure M]
                    [--server ws://HOST:PORT/ws]

Meshes the surface EXPR = 0 (an equation such as 'x^2+y^2+z^2=1', '@model.vm' for a Fidget
model, or '@grid.iso' for a sampled grid at isovalue 0) with an octree and Marching Cubes 33,
every vertex on the surface, and writes it to FILE:
  -o, --output FILE   .glb (glTF 2.0, Draco-compressed, with normals), .stl (binary),
                      .ply (binary little endian, with normals) or .obj
  --param a=1.5       the value of parameter a (repeat for each parameter)
  --box ...           the meshing box (default -5,5,-5,5,-5,5; a grid's own box for .iso)
  --depth MIN,MAX     octree depths: every cell down to MIN is examined, cells are split
                      where needed down to MAX (default 4,9; 0 <= MIN <= MAX <= 16; for
                      .iso the depth whose cells are the grid's cells)
  --threads N         worker threads (default 0: all cores); the mesh does not depend on it
  --stats             print one JSON line: triangles, vertices, evaluations, time_ms,
                      cells, unresolved_cells, certified, ... (with refinement:
                      first_mesh_ms, total_ms, error_total, error_max, splits, merges,
                      certified, unresolved_cells, phase1_meshes, budget_unreachable)
)";

constexpr OptionSpec kOptions[] = {{"output", true, false},  {"param", true, true},
                                   {"box", true, false},     {"depth", true, false},
                                   {"threads", true, false}, {"stats", false, false},
                                   {"server", true, false}};

/// `-o FILE` is accepted as `--output FILE`.
std::vector<std::string_view> expand_short_options(std::span<const std::string_view> args) {
    std::vector<std::string_view> expanded(args.begin(), args.end());
    for (std::string_view& arg : expanded) {
        if (arg == "-o") arg = "--output";
        if (arg == "--") break;
    }
    return expanded;
}

Box parse_mesh_box(std::string_view text) {
    const std::vector<double> v = parse_numbers(text, 6, "--box");
    const Box box{{v[0], v[2], v[4]}, {v[1], v[3], v[5]}};
    if (!(box.lo.x < box.hi.x && box.lo.y < box.hi.y && box.lo.z < box.hi.z)) {
        throw UsageError("--box: each lower bound must be below its upper bound (x0,x1,y0,...)");
    }
    return box;
}

int parse_whole(double value, std::string_view what, int lo, int hi) {
    if (value != std::floor(value) || value < lo || value > hi) {
        throw UsageError(std::string(what) + ": expected a whole number from " +
                         std::to_string(lo) + " to " + std::to_string(hi));
    }
    return static_cast<int>(value);
}

bool names_iso_file(std::string_view source) {
    if (!source.starts_with('@') || source.size() < 5) return false;
    std::string ext(source.substr(source.size() - 4));
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return ext == ".iso";
}

/// The octree depth whose cells are the grid's cells (or smaller, when a sample count less one
/// is not a power of two): MC33 on them has the interpolant's topology. The grid field's interval
/// bounds do not shrink inside a grid cell, so deeper cells would all be split to max depth.
int grid_depth(const IsoGrid& grid) {
    const int cells = std::max({grid.nx, grid.ny, grid.nz}) - 1;
    int depth = 0;
    while ((1 << depth) < cells && depth < 16) ++depth;
    return depth;
}

/// The field of `source`; prints the problem and returns null on failure. For a sampled grid,
/// `depth` is set to grid_depth.
std::shared_ptr<const Field> load_field(std::string_view source,
                                        std::span<const std::string_view> params,
                                        std::optional<int>& depth) {
    if (!names_iso_file(source)) {
        std::optional<FunctionInput> function = load_function(source, params);
        return function ? function->field : nullptr;
    }
    if (!params.empty()) throw UsageError("--param does not apply to a sampled grid");
    std::string error;
    std::optional<IsoGrid> grid = load_iso(std::string(source.substr(1)), &error);
    if (!grid) {
        print_error(error);
        return nullptr;
    }
    depth = grid_depth(*grid);
    return make_grid_field(std::move(*grid));
}

nlohmann::ordered_json stats_json(const PolygonizeStats& stats) {
    nlohmann::ordered_json out;
    out["triangles"] = stats.triangles;
    out["vertices"] = stats.vertices;
    out["evaluations"] = stats.evaluations;
    out["interval_evaluations"] = stats.interval_evaluations;
    out["cells"] = stats.cells;
    out["depth"] = stats.depth;
    out["unresolved_cells"] = stats.unresolved_cells;
    out["certified"] = stats.certified();
    if (stats.region_cells > 0) out["region_cells"] = stats.region_cells;
    out["collapses"] = stats.collapses;
    out["flips"] = stats.flips;
    out["time_ms"] = stats.time_ms;
    return out;
}

}  // namespace

int run_mesh(std::span<const std::string_view> raw_args) {
    const std::vector<std::string_view> expanded = expand_short_options(raw_args);
    std::vector<OptionSpec> specs(std::begin(kOptions), std::end(kOptions));
    specs.insert(specs.end(), std::begin(kRefineOptionSpecs), std::end(kRefineOptionSpecs));
    Arguments args(expanded, specs);
    if (args.help()) {
        std::fputs(kUsage.data(), stdout);
        std::fputs(kRefineUsage.data(), stdout);
        std::fputs(kServerUsage.data(), stdout);
        return 0;
    }
    const RefineOptions refine_options = parse_refine_options(args);
    if (args.positional().size() != 1) {
        throw UsageError("expected one EXPR, got " + std::to_string(args.positional().size()));
    }
    if (!args.has("output")) throw UsageError("missing -o FILE (.glb, .stl, .ply or .obj)");
    PolygonizeSettings settings;
    if (args.has("depth")) {
        const std::vector<double> d = parse_numbers(*args.value("depth"), 2, "--depth");
        settings.min_depth = parse_whole(d[0], "--depth MIN", 0, 16);
        settings.max_depth = parse_whole(d[1], "--depth MAX", 0, 16);
        if (settings.min_depth > settings.max_depth) throw UsageError("--depth: MIN exceeds MAX");
    } else if (refine_options.refine()) {
        settings.min_depth = kRefinePhase1MinDepth;
    }
    if (args.has("threads")) {
        settings.threads =
            parse_whole(parse_number(*args.value("threads"), "--threads"), "--threads", 0, 256);
    }
    const std::string output(*args.value("output"));
    if (!is_export_file_name(output)) {
        throw UsageError("-o: the file name must end in .glb, .stl, .ply or .obj");
    }
    const std::string_view source = args.positional()[0];
    if (args.has("server") &&
        (args.has("depth") || args.has("threads") || names_iso_file(source))) {
        throw UsageError(
            "--server meshes functions with the server's depths and threads: "
            "no --depth, --threads or .iso grid");
    }
    std::optional<int> depth_of_grid;
    const std::shared_ptr<const Field> field =
        load_field(source, args.values("param"), depth_of_grid);
    if (!field) return 1;
    if (depth_of_grid && !args.has("depth")) {
        settings.min_depth = settings.max_depth = *depth_of_grid;
    }
    // A sampled grid has no detail below its cells for the octree to look for.
    if (depth_of_grid) settings.feature_levels = 0;
    if (args.has("box")) {
        settings.box = parse_mesh_box(*args.value("box"));
    } else if (names_iso_file(source)) {
        settings.box = field->domain();
    }

    if (args.has("server")) {
        const protocol::Create request =
            server_request(source, args.values("param"), settings.box, refine_options);
        return mesh_on_server(*args.value("server"), request, output, args.has("stats"));
    }
    std::optional<RefineOutcome> refined;
    std::optional<PolygonizeResult> phase1;
    if (refine_options.refine()) {
        refined = refine(field, settings, refine_options);
    } else {
        phase1 = polygonize(*field, settings);
    }
    if (phase1 && phase1->stats.region_cells > 0) {
        print_warning("the equation holds on a whole region of the box, which is no surface");
    }
    try {
        write_export_file(refined ? refined->mesh : phase1->mesh, output);
    } catch (const std::runtime_error& error) {
        print_error(error.what());
        return 1;
    }
    if (args.has("stats"))
        print_json_line(refined ? refine_stats(*refined) : stats_json(phase1->stats));
    return 0;
}

}  // namespace isomesh::cli
