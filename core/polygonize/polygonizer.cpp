// The polygonization phase (thesis 3.3.2), in the order the data flows:
// 1. octree.h: the leaves where the surface may be, each as deep as its topology needed
//    (interval arithmetic finds what corner sampling misses; cell_classification.h decides when
//    the topology inside a cell is certain);
// 2. corner values of the leaves, evaluated once each, in batches;
// 3. crossings: each crossed leaf edge is narrowed by bisection to the finest lattice step where
//    f changes sign (crossing_vertices.h), which names its vertex, so leaves of different sizes
//    sharing a lattice line share the vertex;
// 4. the octree is graded along the surface (a leaf is split while a neighbour across a face the
//    surface crosses is two levels finer), then Marching Cubes 33 runs in every leaf
//    (leaf_mesher.h), with crack patching where a neighbour is finer; leaves whose faces do not
//    match their finer neighbours are split and everything is meshed again, until all match. The
//    thesis refines every surface cell to one common depth instead, which is simpler but lets one
//    small feature (a thin neck, a crease) refine the whole surface: millions of triangles where
//    tens of thousands suffice;
// 5. one root per crossing used, found on its finest step by safeguarded Newton iteration with
//    the gradient (edge_roots.h); crossings that are poles or jumps are no roots, and the
//    triangles touching them are dropped;
// 6. thin triangle cleanup (thin_triangle_cleanup.h), then adjacency and base edges
//    (mesh/topology.h).
// Every parallel step stores its results by task index and merges them in index order, and
// vertices are numbered by crossing, so the mesh is the same for every thread count.
#include "polygonize/polygonizer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <thread>
#include <unordered_map>
#include <vector>

#include <glm/geometric.hpp>

#include "mesh/topology.h"
#include "polygonize/crossing_vertices.h"
#include "polygonize/edge_roots.h"
#include "polygonize/lattice.h"
#include "polygonize/leaf_index.h"
#include "polygonize/leaf_mesher.h"
#include "polygonize/mc33.h"
#include "polygonize/octree.h"
#include "polygonize/thin_triangle_cleanup.h"
#include "polygonize/worker_pool.h"

namespace isomesh {
namespace {

constexpr std::size_t kPointsPerTask = 1024;
constexpr std::size_t kEdgesPerTask = 256;
constexpr std::size_t kCellsPerTask = 256;
constexpr int kMaxThreads = 256;
/// Cleanup thresholds; the edge length is relative to the lattice step of the deepest leaf.
constexpr double kMinEdgeFraction = 0.1;
constexpr double kMinQuality = 0.1;

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
    if (s.threads < 0 || s.threads > kMaxThreads) {
        throw std::invalid_argument("threads must be between 0 (all cores) and " +
                                    std::to_string(kMaxThreads));
    }
}

int thread_count(int requested) {
    if (requested > 0) return requested;
    return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

bool is_cancelled(const PolygonizeSettings& s) {
    return s.cancel != nullptr && s.cancel->load(std::memory_order_relaxed);
}

glm::dvec3 unit_or_zero(const glm::dvec3& v) {
    const double length = glm::length(v);
    return length > 0.0 && std::isfinite(length) ? v / length : glm::dvec3(0.0);
}

std::size_t task_count(std::size_t items, std::size_t per_task) {
    return (items + per_task - 1) / per_task;
}

using ValueMap = std::unordered_map<std::uint64_t, double>;

/// Evaluates f, in batches, at the corners of `leaves` not in `values`.
void evaluate_corners(WorkerPool& workers, const Lattice& lattice,
                      const std::vector<CellId>& leaves, ValueMap& values) {
    std::vector<std::uint64_t> missing;
    for (const CellId& cell : leaves) {
        for (int c = 0; c < 8; ++c) {
            const std::uint64_t key = Lattice::key(lattice.corner(cell, c));
            if (!values.contains(key)) missing.push_back(key);
        }
    }
    std::sort(missing.begin(), missing.end());
    missing.erase(std::unique(missing.begin(), missing.end()), missing.end());
    std::vector<double> results(missing.size());
    workers.for_each(task_count(missing.size(), kPointsPerTask),
                     [&](std::size_t task, CountingEvaluator& evaluator) {
                         const std::size_t begin = task * kPointsPerTask;
                         const std::size_t n = std::min(kPointsPerTask, missing.size() - begin);
                         std::vector<double> x(n), y(n), z(n);
                         for (std::size_t i = 0; i < n; ++i) {
                             const glm::dvec3 p = lattice.point(Lattice::unkey(missing[begin + i]));
                             x[i] = p.x;
                             y[i] = p.y;
                             z[i] = p.z;
                         }
                         evaluator.values({x, y, z}, std::span(results).subspan(begin, n));
                     });
    for (std::size_t i = 0; i < missing.size(); ++i) values.emplace(missing[i], results[i]);
}

/// Locates the crossing of every edge of `leaves` whose ends are on different sides and that is
/// not in `crossings` yet (crossing_vertices.h), adding the values it evaluates to `values`.
void locate_crossings(WorkerPool& workers, const Lattice& lattice,
                      const std::vector<CellId>& leaves, ValueMap& values,
                      std::unordered_map<std::uint64_t, CrossingKey>& crossings) {
    struct Edge {
        std::uint64_t key;
        glm::u32vec3 lower;
        int axis;
        int depth;
    };
    std::vector<Edge> edges;
    for (const CellId& cell : leaves) {
        for (int e = 0; e < 12; ++e) {
            const auto [c0, c1] = kEdgeCorners[e];
            const glm::u32vec3 p0 = lattice.corner(cell, c0);
            if (is_inside(values.at(Lattice::key(p0))) ==
                is_inside(values.at(Lattice::key(lattice.corner(cell, c1))))) {
                continue;
            }
            const std::uint64_t key = cell_edge_key(p0, e / 4, cell.depth);
            if (!crossings.contains(key)) edges.push_back({key, p0, e / 4, cell.depth});
        }
    }
    std::sort(edges.begin(), edges.end(),
              [](const Edge& a, const Edge& b) { return a.key < b.key; });
    edges.erase(std::unique(edges.begin(), edges.end(),
                            [](const Edge& a, const Edge& b) { return a.key == b.key; }),
                edges.end());
    std::vector<CrossingKey> located(edges.size());
    std::vector<ValueMap> evaluated(task_count(edges.size(), kEdgesPerTask));
    workers.for_each(evaluated.size(), [&](std::size_t task, CountingEvaluator& evaluator) {
        CornerCache cache(evaluator, lattice, &values);
        const std::size_t end = std::min(edges.size(), (task + 1) * kEdgesPerTask);
        for (std::size_t i = task * kEdgesPerTask; i < end; ++i) {
            located[i] =
                locate_crossing(cache, lattice, edges[i].lower, edges[i].axis, edges[i].depth);
        }
        evaluated[task] = std::move(cache.values());
    });
    for (ValueMap& part : evaluated) values.merge(part);
    for (std::size_t i = 0; i < edges.size(); ++i) crossings.emplace(edges[i].key, located[i]);
}

/// Replaces each leaf of `which` (a subsequence of `leaves`) by the leaves of its subtree,
/// keeping the octree order; the new leaves are appended to `added`.
std::vector<CellId> split_leaves(WorkerPool& workers, const Lattice& lattice,
                                 const OctreeSettings& settings, const std::vector<CellId>& leaves,
                                 const std::vector<CellId>& which, ValueMap& values,
                                 std::size_t& unresolved, std::vector<CellId>& added) {
    std::vector<OctreeLeaves> subtrees(which.size());
    workers.for_each(which.size(), [&](std::size_t i, CountingEvaluator& evaluator) {
        subtrees[i] = split_leaf(evaluator, lattice, settings, which[i], values);
    });
    std::vector<CellId> result;
    std::size_t next = 0;
    for (const CellId& leaf : leaves) {
        if (next < which.size() && leaf.coords == which[next].coords &&
            leaf.depth == which[next].depth) {
            OctreeLeaves& subtree = subtrees[next++];
            result.insert(result.end(), subtree.leaves.begin(), subtree.leaves.end());
            added.insert(added.end(), subtree.leaves.begin(), subtree.leaves.end());
            values.merge(subtree.known_values);
            unresolved += subtree.unresolved;
        } else {
            result.push_back(leaf);
        }
    }
    return result;
}

/// The leaves for which `predicate` holds, in order (evaluated in parallel).
template <typename Predicate>
std::vector<CellId> select(WorkerPool& workers, const std::vector<CellId>& leaves,
                           const Predicate& predicate) {
    std::vector<std::uint8_t> chosen(leaves.size());
    workers.for_each(task_count(leaves.size(), kCellsPerTask), [&](std::size_t task, auto&) {
        const std::size_t end = std::min(leaves.size(), (task + 1) * kCellsPerTask);
        for (std::size_t i = task * kCellsPerTask; i < end; ++i) chosen[i] = predicate(leaves[i]);
    });
    std::vector<CellId> result;
    for (std::size_t i = 0; i < leaves.size(); ++i) {
        if (chosen[i]) result.push_back(leaves[i]);
    }
    return result;
}

/// The surface's vertices on lattice edges: roots on the finest steps of the crossings used.
struct CrossingRoots {
    std::vector<CrossingKey> keys;  // sorted
    std::vector<EdgeRoot> roots;
};

CrossingRoots find_roots(WorkerPool& workers, const Lattice& lattice, const ValueMap& values,
                         const std::vector<LeafMeshes>& parts) {
    CrossingRoots result;
    for (const LeafMeshes& part : parts) {
        for (const auto& triangle : part.triangles) {
            for (VertexRef v : triangle) {
                if (!(v & kExtraVertex)) result.keys.push_back(v);
            }
        }
    }
    std::sort(result.keys.begin(), result.keys.end());
    result.keys.erase(std::unique(result.keys.begin(), result.keys.end()), result.keys.end());
    result.roots.resize(result.keys.size());
    workers.for_each(task_count(result.keys.size(), kEdgesPerTask),
                     [&](std::size_t task, CountingEvaluator& evaluator) {
                         const std::size_t end =
                             std::min(result.keys.size(), (task + 1) * kEdgesPerTask);
                         for (std::size_t i = task * kEdgesPerTask; i < end; ++i) {
                             result.roots[i] = find_edge_root(
                                 evaluator, crossing_segment(values, lattice, result.keys[i]));
                         }
                     });
    return result;
}

/// The mesh: a vertex per crossing that is a root, then the leaves' own vertices; triangles
/// touching a crossing that is not a root (a pole, a jump) are left out.
Mesh assemble(const CrossingRoots& crossings, const std::vector<LeafMeshes>& parts) {
    constexpr std::uint32_t kNone = 0xffffffffu;
    Mesh mesh;
    std::vector<std::uint32_t> id(crossings.keys.size(), kNone);
    for (std::size_t i = 0; i < crossings.keys.size(); ++i) {
        if (!crossings.roots[i].found) continue;
        id[i] = static_cast<std::uint32_t>(mesh.positions.size());
        mesh.positions.push_back(crossings.roots[i].position);
        mesh.normals.push_back(unit_or_zero(crossings.roots[i].gradient));
    }
    for (const LeafMeshes& part : parts) {
        const auto offset = static_cast<std::uint32_t>(mesh.positions.size());
        for (const auto& triangle : part.triangles) {
            std::array<std::uint32_t, 3> t;
            for (int k = 0; k < 3; ++k) {
                const VertexRef v = triangle[k];
                if (v & kExtraVertex) {
                    t[k] = offset + static_cast<std::uint32_t>(v & ~kExtraVertex);
                } else {
                    const auto it =
                        std::lower_bound(crossings.keys.begin(), crossings.keys.end(), v);
                    t[k] = id[static_cast<std::size_t>(it - crossings.keys.begin())];
                }
            }
            if (t[0] != kNone && t[1] != kNone && t[2] != kNone) mesh.triangles.push_back(t);
        }
        mesh.positions.insert(mesh.positions.end(), part.extra_positions.begin(),
                              part.extra_positions.end());
        mesh.normals.insert(mesh.normals.end(), part.extra_normals.begin(),
                            part.extra_normals.end());
    }
    return mesh;
}

/// Bit 2 * axis + side for each face of `box` the vertex lies on.
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

}  // namespace

PolygonizeResult polygonize(const Field& field, const PolygonizeSettings& settings) {
    validate(settings);
    const auto start = std::chrono::steady_clock::now();
    PolygonizeResult result;
    PolygonizeStats& stats = result.stats;
    WorkerPool workers(field, thread_count(settings.threads));
    const Lattice lattice(settings.box, settings.max_depth);
    auto finish = [&] {
        stats.evaluations = workers.point_evaluations();
        stats.interval_evaluations = workers.interval_evaluations();
        stats.cancelled = is_cancelled(settings);
        if (stats.cancelled) result.mesh = Mesh{};
        stats.triangles = result.mesh.triangle_count();
        stats.vertices = result.mesh.vertex_count();
        stats.time_ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
        return std::move(result);
    };

    const OctreeSettings octree_settings{settings.min_depth, settings.max_depth, settings.cancel};
    OctreeLeaves octree = find_leaves(workers, lattice, octree_settings);
    stats.unresolved_cells = octree.unresolved;
    std::vector<CellId> leaves = std::move(octree.leaves);
    ValueMap values = std::move(octree.known_values);
    std::unordered_map<std::uint64_t, CrossingKey> crossings;
    std::vector<LeafMeshes> parts;
    std::vector<CellId> fresh = leaves;      // leaves whose corners are not evaluated yet
    std::vector<CellId> unlocated = leaves;  // leaves whose crossings are not located yet
    auto split = [&](const std::vector<CellId>& which) {
        const std::size_t before = fresh.size();
        leaves = split_leaves(workers, lattice, octree_settings, leaves, which, values,
                              stats.unresolved_cells, fresh);
        unlocated.insert(unlocated.end(), fresh.begin() + before, fresh.end());
    };
    // Grade the octree along the surface, then mesh every leaf; split the leaves whose faces do
    // not match their finer neighbours, and again, until all match (leaves of equal size always
    // do, so this ends).
    while (!is_cancelled(settings)) {
        evaluate_corners(workers, lattice, fresh, values);
        fresh.clear();
        const LeafIndex index(leaves);
        const LeafMeshingInput input{lattice, values, crossings, index};
        const std::vector<CellId> ungraded =
            select(workers, leaves, [&](const CellId& leaf) { return needs_grading(input, leaf); });
        if (!ungraded.empty()) {
            split(ungraded);
            continue;
        }
        locate_crossings(workers, lattice, unlocated, values, crossings);
        unlocated.clear();
        parts.assign(task_count(leaves.size(), kCellsPerTask), {});
        workers.for_each(parts.size(), [&](std::size_t task, CountingEvaluator& evaluator) {
            const std::size_t end = std::min(leaves.size(), (task + 1) * kCellsPerTask);
            for (std::size_t i = task * kCellsPerTask; i < end; ++i) {
                mesh_leaf(evaluator, input, leaves[i], parts[task]);
            }
        });
        std::vector<CellId> unmatched;
        for (const LeafMeshes& part : parts) {
            unmatched.insert(unmatched.end(), part.unmatched.begin(), part.unmatched.end());
        }
        if (unmatched.empty()) break;
        split(unmatched);
    }
    stats.cells = leaves.size();
    for (const CellId& leaf : leaves) stats.depth = std::max(stats.depth, leaf.depth);
    if (is_cancelled(settings)) return finish();

    result.mesh = assemble(find_roots(workers, lattice, values, parts), parts);
    const glm::dvec3 step = lattice.box().size() / std::ldexp(1.0, stats.depth);
    const ThinTriangleSettings cleanup{kMinEdgeFraction * std::min({step.x, step.y, step.z}),
                                       kMinQuality};
    const ThinTriangleReport report =
        remove_thin_triangles(result.mesh, box_faces(result.mesh, settings.box), cleanup);
    stats.collapses = report.collapses;
    stats.flips = report.flips;
    build_adjacency(result.mesh);
    return finish();
}

}  // namespace isomesh
