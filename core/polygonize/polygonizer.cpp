// The polygonization phase (thesis 3.3.2), in the order the data flows:
// 1. octree.h: the cells of one common depth where the surface is (interval arithmetic finds
//    what corner sampling misses; cell_classification.h decides when the topology is certain);
// 2. corner values of those cells, evaluated once each, in batches;
// 3. one vertex per crossed lattice edge, by root finding along the edge (edge_roots.h), shared
//    by the four cells around the edge; crossings that are poles or jumps get none, and the cells
//    around them are not meshed;
// 4. Marching Cubes 33 in every cell (mc33.h), with its interior vertex projected onto the
//    surface (vertex_projection.h);
// 5. thin triangle cleanup (thin_triangle_cleanup.h), then adjacency and base edges
//    (mesh/topology.h).
// Every parallel step stores its results by task index and merges them in index order, and
// vertices are numbered by lattice edge, so the mesh is the same for every thread count.
#include "polygonize/polygonizer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <thread>
#include <vector>

#include <glm/geometric.hpp>

#include "mesh/topology.h"
#include "polygonize/edge_roots.h"
#include "polygonize/lattice.h"
#include "polygonize/mc33.h"
#include "polygonize/octree.h"
#include "polygonize/thin_triangle_cleanup.h"
#include "polygonize/vertex_projection.h"
#include "polygonize/worker_pool.h"

namespace isomesh {
namespace {

constexpr std::size_t kPointsPerTask = 1024;
constexpr std::size_t kEdgesPerTask = 256;
constexpr std::size_t kCellsPerTask = 256;
constexpr int kMaxThreads = 256;
/// Cleanup thresholds, relative to the lattice step at the common depth.
constexpr double kMinEdgeFraction = 0.1;
constexpr double kMinQuality = 0.1;
/// Marks a triangle corner that refers to a task's own interior vertex (by its local index).
constexpr std::uint32_t kLocalVertex = 0x80000000u;

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

/// Values of f at sorted lattice keys.
struct CornerTable {
    std::vector<std::uint64_t> keys;
    std::vector<double> values;

    double at(std::uint64_t key) const {
        const auto it = std::lower_bound(keys.begin(), keys.end(), key);
        return values[static_cast<std::size_t>(it - keys.begin())];
    }
};

CornerTable evaluate_corners(WorkerPool& workers, const Lattice& lattice,
                             const SurfaceCells& surface) {
    CornerTable table;
    table.keys.reserve(surface.cells.size() * 8);
    for (const CellId& cell : surface.cells) {
        for (int c = 0; c < 8; ++c) table.keys.push_back(Lattice::key(lattice.corner(cell, c)));
    }
    std::sort(table.keys.begin(), table.keys.end());
    table.keys.erase(std::unique(table.keys.begin(), table.keys.end()), table.keys.end());
    table.values.assign(table.keys.size(), 0.0);
    std::vector<std::size_t> missing;
    for (std::size_t i = 0; i < table.keys.size(); ++i) {
        const auto known = surface.known_values.find(table.keys[i]);
        if (known != surface.known_values.end()) {
            table.values[i] = known->second;
        } else {
            missing.push_back(i);
        }
    }
    workers.for_each(task_count(missing.size(), kPointsPerTask), [&](std::size_t task,
                                                                     CountingEvaluator& evaluator) {
        const std::size_t begin = task * kPointsPerTask;
        const std::size_t n = std::min(kPointsPerTask, missing.size() - begin);
        std::vector<double> x(n), y(n), z(n), out(n);
        for (std::size_t i = 0; i < n; ++i) {
            const glm::dvec3 p = lattice.point(Lattice::unkey(table.keys[missing[begin + i]]));
            x[i] = p.x;
            y[i] = p.y;
            z[i] = p.z;
        }
        evaluator.values({x, y, z}, out);
        for (std::size_t i = 0; i < n; ++i) table.values[missing[begin + i]] = out[i];
    });
    return table;
}

/// The lattice edges crossed by the surface (ends on different sides), sorted by edge key.
struct CrossedEdges {
    std::vector<std::uint64_t> keys;
    std::vector<EdgeRoot> roots;
    std::vector<std::uint32_t> vertex;  ///< mesh vertex of each edge (kNoVertex without a root)

    static constexpr std::uint32_t kNoVertex = 0xffffffffu;

    std::uint32_t vertex_of(std::uint64_t key) const {
        const auto it = std::lower_bound(keys.begin(), keys.end(), key);
        return vertex[static_cast<std::size_t>(it - keys.begin())];
    }
};

EdgeSegment lattice_edge(const Lattice& lattice, const CornerTable& corners,
                         const glm::u32vec3& lower, int axis, std::uint32_t span) {
    glm::u32vec3 upper = lower;
    upper[axis] += span;
    return {lattice.point(lower), lattice.point(upper), corners.at(Lattice::key(lower)),
            corners.at(Lattice::key(upper)), axis};
}

CrossedEdges find_crossings(WorkerPool& workers, const Lattice& lattice,
                            const SurfaceCells& surface, const CornerTable& corners) {
    CrossedEdges edges;
    for (const CellId& cell : surface.cells) {
        for (int e = 0; e < 12; ++e) {
            const auto [c0, c1] = kEdgeCorners[e];
            const glm::u32vec3 p0 = lattice.corner(cell, c0);
            if (is_inside(corners.at(Lattice::key(p0))) !=
                is_inside(corners.at(Lattice::key(lattice.corner(cell, c1))))) {
                edges.keys.push_back(Lattice::edge_key(p0, e / 4));
            }
        }
    }
    std::sort(edges.keys.begin(), edges.keys.end());
    edges.keys.erase(std::unique(edges.keys.begin(), edges.keys.end()), edges.keys.end());
    edges.roots.resize(edges.keys.size());
    const std::uint32_t span = lattice.span(surface.depth);
    workers.for_each(task_count(edges.keys.size(), kEdgesPerTask),
                     [&](std::size_t task, CountingEvaluator& evaluator) {
                         const std::size_t end =
                             std::min(edges.keys.size(), (task + 1) * kEdgesPerTask);
                         for (std::size_t i = task * kEdgesPerTask; i < end; ++i) {
                             const std::uint64_t key = edges.keys[i];
                             const EdgeSegment edge = lattice_edge(
                                 lattice, corners, Lattice::unkey(key & ((1ull << 51) - 1)),
                                 static_cast<int>(key >> 51), span);
                             edges.roots[i] = find_edge_root(evaluator, edge);
                         }
                     });
    edges.vertex.assign(edges.keys.size(), CrossedEdges::kNoVertex);
    std::uint32_t next = 0;
    for (std::size_t i = 0; i < edges.keys.size(); ++i) {
        if (edges.roots[i].found) edges.vertex[i] = next++;
    }
    return edges;
}

/// MC33 needs finite values; signs are what matters at non-finite corners (a pole's corner,
/// NaN outside f's domain counting as outside).
std::array<double, 8> finite_values(std::array<double, 8> values) {
    double largest = 0.0;
    for (double v : values) {
        if (std::isfinite(v)) largest = std::max(largest, std::abs(v));
    }
    const double big = largest > 0.0 ? 2.0 * largest : 1.0;
    for (double& v : values) {
        if (!std::isfinite(v)) v = is_inside(v) ? -big : big;
    }
    return values;
}

struct CellMeshes {
    std::vector<std::array<std::uint32_t, 3>> triangles;
    std::vector<glm::dvec3> interior_positions;
    std::vector<glm::dvec3> interior_normals;
};

class CellMesher {
  public:
    CellMesher(Evaluator& evaluator, const Lattice& lattice, const CornerTable& corners,
               const CrossedEdges& edges, CellMeshes& out)
        : evaluator_(evaluator), lattice_(lattice), corners_(corners), edges_(edges), out_(out) {}

    void mesh(const CellId& cell) {
        std::array<double, 8> values;
        for (int c = 0; c < 8; ++c) values[c] = corners_.at(Lattice::key(lattice_.corner(cell, c)));
        const CellTriangulation tri = triangulate_cell(finite_values(values));
        if (tri.triangle_count == 0) return;
        std::array<std::uint32_t, 13> ids;
        ids.fill(CrossedEdges::kNoVertex);
        for (int e = 0; e < 12; ++e) {
            const auto [c0, c1] = kEdgeCorners[e];
            if (is_inside(values[c0]) == is_inside(values[c1])) continue;
            ids[e] = edges_.vertex_of(Lattice::edge_key(lattice_.corner(cell, c0), e / 4));
            if (ids[e] == CrossedEdges::kNoVertex) return;  // a pole or a jump: no surface here
        }
        if (tri.uses_interior_vertex()) ids[kInteriorVertex] = interior_vertex(cell, tri, ids);
        for (int t = 0; t < tri.triangle_count; ++t) {
            const auto& v = tri.triangles[t];
            const std::array<std::uint32_t, 3> triangle{ids[v[0]], ids[v[1]], ids[v[2]]};
            // Only when the interior vertex fell back onto an edge vertex (see below).
            if (triangle[0] == triangle[1] || triangle[1] == triangle[2] ||
                triangle[2] == triangle[0]) {
                continue;
            }
            out_.triangles.push_back(triangle);
        }
    }

  private:
    /// The mean of the crossings of the loop the vertex fans, projected onto the surface inside
    /// the cell. If the projection fails, the fan is rebuilt around one of the loop's vertices
    /// instead (the fan triangles through it vanish, leaving a fan triangulation of the loop).
    std::uint32_t interior_vertex(const CellId& cell, const CellTriangulation& tri,
                                  const std::array<std::uint32_t, 13>& ids) {
        glm::dvec3 sum(0.0);
        int count = 0;
        std::uint32_t fallback = CrossedEdges::kNoVertex;
        for (int e = 0; e < 12; ++e) {
            if (!((tri.interior_vertex_edges >> e) & 1u)) continue;
            const auto [c0, c1] = kEdgeCorners[e];
            const std::uint64_t key = Lattice::edge_key(lattice_.corner(cell, c0), e / 4);
            const auto it = std::lower_bound(edges_.keys.begin(), edges_.keys.end(), key);
            sum += edges_.roots[static_cast<std::size_t>(it - edges_.keys.begin())].position;
            ++count;
            if (fallback == CrossedEdges::kNoVertex) fallback = ids[e];
        }
        const SurfacePoint point = project_to_surface(evaluator_, sum / static_cast<double>(count),
                                                      lattice_.cell_box(cell));
        if (!point.on_surface) return fallback;
        out_.interior_positions.push_back(point.position);
        out_.interior_normals.push_back(unit_or_zero(point.gradient));
        return kLocalVertex | static_cast<std::uint32_t>(out_.interior_positions.size() - 1);
    }

    Evaluator& evaluator_;
    const Lattice& lattice_;
    const CornerTable& corners_;
    const CrossedEdges& edges_;
    CellMeshes& out_;
};

Mesh assemble(const CrossedEdges& edges, std::vector<CellMeshes>& parts) {
    Mesh mesh;
    for (std::size_t i = 0; i < edges.keys.size(); ++i) {
        if (edges.vertex[i] == CrossedEdges::kNoVertex) continue;
        mesh.positions.push_back(edges.roots[i].position);
        mesh.normals.push_back(unit_or_zero(edges.roots[i].gradient));
    }
    for (CellMeshes& part : parts) {
        const auto offset = static_cast<std::uint32_t>(mesh.positions.size());
        for (auto triangle : part.triangles) {
            for (std::uint32_t& v : triangle) {
                if (v & kLocalVertex) v = offset + (v & ~kLocalVertex);
            }
            mesh.triangles.push_back(triangle);
        }
        mesh.positions.insert(mesh.positions.end(), part.interior_positions.begin(),
                              part.interior_positions.end());
        mesh.normals.insert(mesh.normals.end(), part.interior_normals.begin(),
                            part.interior_normals.end());
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

    const SurfaceCells surface = find_surface_cells(
        workers, lattice, {settings.min_depth, settings.max_depth, settings.cancel});
    stats.depth = surface.depth;
    stats.cells = surface.cells.size();
    stats.unresolved_cells = surface.unresolved;
    if (surface.cells.empty() || is_cancelled(settings)) return finish();

    const CornerTable corners = evaluate_corners(workers, lattice, surface);
    if (is_cancelled(settings)) return finish();
    const CrossedEdges edges = find_crossings(workers, lattice, surface, corners);
    if (is_cancelled(settings)) return finish();

    std::vector<CellMeshes> parts(task_count(surface.cells.size(), kCellsPerTask));
    workers.for_each(parts.size(), [&](std::size_t task, CountingEvaluator& evaluator) {
        CellMesher mesher(evaluator, lattice, corners, edges, parts[task]);
        const std::size_t end = std::min(surface.cells.size(), (task + 1) * kCellsPerTask);
        for (std::size_t i = task * kCellsPerTask; i < end; ++i) mesher.mesh(surface.cells[i]);
    });
    result.mesh = assemble(edges, parts);

    const glm::dvec3 step = lattice.box().size() / std::ldexp(1.0, surface.depth);
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
