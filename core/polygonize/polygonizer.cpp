// The polygonization phase (thesis 3.3.2), in the order the data flows:
// 1. octree.h: the leaves where the surface may be, each as deep as its topology needed
//    (interval arithmetic finds what corner sampling misses; cell_classification.h decides when
//    the topology inside a cell is certain), classified a slice at a time, largest first;
// 2-6. the mesh of the octree's frontier as it stands (final once every cell is classified):
//    corner values, crossings, grading and Marching Cubes 33 with crack patching, roots, thin
//    triangle cleanup and adjacency (frontier_mesher.h, whose file comment details each step).
// Every parallel step stores its results by task index and merges them in index order, and
// vertices are numbered by crossing, so the mesh is the same for every thread count.
#include "polygonize/polygonizer.h"

#include <algorithm>
#include <chrono>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "polygonize/frontier_mesher.h"

namespace isomesh {
namespace {

constexpr int kMaxThreads = 256;

int thread_count(int requested) {
    if (requested > 0) return requested;
    return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

OctreeSettings octree_settings(const PolygonizeSettings& s) {
    OctreeSettings o;
    o.min_depth = s.min_depth;
    o.max_depth = s.max_depth;
    o.feature_depth = std::min(kMaxOctreeDepth, s.max_depth + s.feature_levels);
    o.max_cells = s.max_cells;
    return o;
}

}  // namespace

std::vector<std::uint8_t> box_faces(const Mesh& mesh, const Box& box) {
    std::vector<std::uint8_t> faces(mesh.positions.size(), 0);
    for (std::size_t v = 0; v < faces.size(); ++v) {
        for (int axis = 0; axis < 3; ++axis) {
            if (mesh.positions[v][axis] == box.lo[axis]) faces[v] |= 1u << (2 * axis);
            if (mesh.positions[v][axis] == box.hi[axis]) faces[v] |= 1u << (2 * axis + 1);
        }
    }
    return faces;
}

void validate(const PolygonizeSettings& s) {
    for (int axis = 0; axis < 3; ++axis) {
        if (!std::isfinite(s.box.lo[axis]) || !std::isfinite(s.box.hi[axis]) ||
            !(s.box.lo[axis] < s.box.hi[axis])) {
            throw std::invalid_argument(
                "the meshing box must be finite with lo < hi on every axis");
        }
    }
    if (s.min_depth < 0 || s.max_depth > kMaxOctreeDepth || s.min_depth > s.max_depth) {
        throw std::invalid_argument("octree depths must satisfy 0 <= min <= max <= " +
                                    std::to_string(kMaxOctreeDepth));
    }
    if (s.feature_levels < 0) throw std::invalid_argument("feature_levels must be >= 0");
    if (s.max_cells < 8) throw std::invalid_argument("max_cells must be at least 8");
    if (s.threads < 0 || s.threads > kMaxThreads) {
        throw std::invalid_argument("threads must be between 0 (all cores) and " +
                                    std::to_string(kMaxThreads));
    }
}

namespace {
const PolygonizeSettings& validated(const PolygonizeSettings& settings) {
    validate(settings);
    return settings;
}

const std::shared_ptr<const Field>& non_null(const std::shared_ptr<const Field>& field) {
    if (!field) throw std::invalid_argument("Polygonizer: null field");
    return field;
}
}  // namespace

Polygonizer::Polygonizer(std::shared_ptr<const Field> field, const PolygonizeSettings& settings)
    : field_(non_null(field)),
      settings_(validated(settings)),
      pool_(*field_, thread_count(settings.threads), settings.helpers),
      lattice_(settings.box, kMaxOctreeDepth),
      octree_(lattice_, octree_settings(settings)) {}

void Polygonizer::advance(const WorkBudget& budget, std::size_t max_frontier) {
    octree_.advance(pool_, values_, budget, max_frontier);
}

Polygonizer::~Polygonizer() = default;

PolygonizeResult Polygonizer::mesh(const WorkBudget& budget) {
    slicing_.reset();
    std::optional<PolygonizeResult> result = mesh_slice(WorkBudget(budget.cancel_flag()));
    if (result) return std::move(*result);
    PolygonizeResult cancelled;
    cancelled.stats.cancelled = true;
    return cancelled;
}

std::optional<PolygonizeResult> Polygonizer::mesh_slice(const WorkBudget& budget,
                                                        std::size_t max_cells) {
    if (!slicing_) {
        slicing_ = std::make_unique<Slicing>();
        slicing_->points_before = pool_.point_evaluations();
        slicing_->intervals_before = pool_.interval_evaluations();
        if (!octree_.found_region()) {
            slicing_->mesher = std::make_unique<FrontierMesher>(
                pool_, lattice_, octree_.settings(), values_,
                coarsened(octree_.frontier(), max_cells), settings_.adjacency);
        }
    }
    const auto start = std::chrono::steady_clock::now();
    const bool done = !slicing_->mesher || slicing_->mesher->advance(budget);
    slicing_->time += std::chrono::steady_clock::now() - start;
    if (budget.cancelled()) slicing_.reset();  // a cancelled mesh is started again
    if (!done || !slicing_) return std::nullopt;
    PolygonizeResult result;
    if (slicing_->mesher) {
        result = slicing_->mesher->take();
    } else {
        result.stats.region_cells = octree_.counts().regions;
    }
    PolygonizeStats& stats = result.stats;
    stats.evaluations = pool_.point_evaluations() - slicing_->points_before;
    stats.interval_evaluations = pool_.interval_evaluations() - slicing_->intervals_before;
    stats.triangles = result.mesh.triangle_count();
    stats.vertices = result.mesh.vertex_count();
    stats.time_ms = std::chrono::duration<double, std::milli>(slicing_->time).count();
    slicing_.reset();
    return result;
}

PolygonizeResult polygonize(const Field& field, const PolygonizeSettings& settings) {
    const auto start = std::chrono::steady_clock::now();
    // Not owned: the field outlives this call.
    Polygonizer polygonizer(std::shared_ptr<const Field>(&field, [](const Field*) {}), settings);
    const WorkBudget budget(settings.cancel);
    polygonizer.advance(budget);
    PolygonizeResult result = polygonizer.mesh(budget);
    result.stats.evaluations = polygonizer.evaluations();
    result.stats.interval_evaluations = polygonizer.interval_evaluations();
    result.stats.cancelled = budget.cancelled();
    if (result.stats.cancelled) result.mesh = Mesh{};
    result.stats.triangles = result.mesh.triangle_count();
    result.stats.vertices = result.mesh.vertex_count();
    result.stats.time_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return result;
}

}  // namespace isomesh
