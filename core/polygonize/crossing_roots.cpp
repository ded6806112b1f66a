// The crossings' roots and the mesh assembled from them (crossing_roots.h).
#include "polygonize/crossing_roots.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>

#include <glm/geometric.hpp>

#include "polygonize/ancestor_path.h"

namespace isomesh {
namespace {

constexpr std::size_t kCrossingsPerTask = 256;

glm::dvec3 unit_or_zero(const glm::dvec3& v) {
    const double length = glm::length(v);
    return length > 0.0 && std::isfinite(length) ? v / length : glm::dvec3(0.0);
}

/// The cells, kRootGroupLevels above the finest, whose specialised tape serves the root finding
/// of the crossings inside them (per-cell tape simplification: a CAD model's min and max branches
/// mostly drop out there). One push per segment cost as much as it saved; per group it is paid
/// once, and the groups are walked to through their ancestors (find_roots). Two, three and four
/// levels cost about the same on colonnade.vm and bear.vm at depth 3,7; three a few % less.
constexpr int kRootGroupLevels = 3;

/// The cell at `depth` holding the finest step `key` (closed boxes: a step on the upper face of
/// the lattice is in the last cell).
CellId root_group(const Lattice& lattice, CrossingKey key, int depth) {
    constexpr std::uint64_t kPointBits = (std::uint64_t{1} << 51) - 1;
    const glm::u32vec3 lower = Lattice::unkey(key & kPointBits);
    const std::uint32_t last = (1u << depth) - 1;
    CellId cell;
    cell.depth = depth;
    for (int axis = 0; axis < 3; ++axis)
        cell.coords[axis] = std::min(last, lower[axis] / lattice.span(depth));
    return cell;
}

/// Finds the roots of crossings order[first, last) of `crossings`, all of one group, with the
/// evaluator specialised to the group's cell (`path` walks to it), in lockstep batches
/// (find_edge_roots), the budget's cancellation checked between batches. (Specialisation does
/// not change any evaluation's result: the roots are those of the whole tape.)
void find_group_roots(AncestorPath& path, Evaluator& evaluator, const Lattice& lattice,
                      const ValueMap& values, CrossingRoots& crossings, std::size_t first,
                      std::size_t last, const WorkBudget& budget) {
    std::vector<EdgeSegment> segments;
    segments.reserve(last - first);
    for (std::size_t k = first; k < last; ++k)
        segments.push_back(crossing_segment(values, lattice, crossings.keys[crossings.order[k]]));
    std::vector<EdgeRoot> roots(segments.size());
    path.walk_to(crossings.groups[crossings.order[first]]);
    constexpr std::size_t kRootsBetweenChecks = 16;
    for (std::size_t i = 0; i < segments.size() && !budget.cancelled(); i += kRootsBetweenChecks) {
        const std::size_t n = std::min(kRootsBetweenChecks, segments.size() - i);
        find_edge_roots(evaluator, std::span(segments).subspan(i, n),
                        std::span(roots).subspan(i, n));
    }
    for (std::size_t k = first; k < last; ++k)
        crossings.roots[crossings.order[k]] = roots[k - first];
}

}  // namespace

CrossingRoots crossings_used(const std::vector<LeafMeshes>& parts, const Lattice& lattice,
                             int finest_depth) {
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
    const int depth = std::max(0, finest_depth - kRootGroupLevels);
    std::vector<std::uint64_t> group_order(result.keys.size());
    for (std::size_t i = 0; i < result.keys.size(); ++i) {
        result.groups.push_back(root_group(lattice, result.keys[i], depth));
        group_order[i] = lattice.octree_order(result.groups.back());
        result.order.push_back(i);
    }
    std::stable_sort(result.order.begin(), result.order.end(),
                     [&](std::size_t a, std::size_t b) { return group_order[a] < group_order[b]; });
    return result;
}

// The groups in octree order: the walk to each group's cell keeps the ancestors it shares with the
// previous
/// one, and each push simplifies its parent's tape, not the whole tape (colonnade.vm: one push
/// of each group from the whole tape was three quarters of the roots' time).
void find_roots(EvaluatorPool& workers, const Lattice& lattice, const ValueMap& values,
                CrossingRoots& crossings, std::size_t begin, std::size_t end,
                const WorkBudget& budget) {
    workers.for_each(task_count(end - begin, kCrossingsPerTask), [&](std::size_t task,
                                                                     CountingEvaluator& evaluator) {
        const std::size_t first = begin + task * kCrossingsPerTask;
        const std::size_t last = std::min(end, first + kCrossingsPerTask);
        AncestorPath path(evaluator, lattice);
        for (std::size_t k = first; k < last && !budget.cancelled();) {
            const CellId& group = crossings.groups[crossings.order[k]];
            std::size_t run = k + 1;
            while (run < last && crossings.groups[crossings.order[run]] == group) ++run;
            find_group_roots(path, evaluator, lattice, values, crossings, k, run, budget);
            k = run;
        }
    });
}

Mesh assemble_mesh(const CrossingRoots& crossings, const std::vector<LeafMeshes>& parts) {
    constexpr std::uint32_t kNone = 0xffffffffu;
    Mesh mesh;
    std::vector<std::uint32_t> id(crossings.keys.size(), kNone);
    for (std::size_t i = 0; i < crossings.keys.size(); ++i) {
        if (!crossings.roots[i].found) continue;
        id[i] = static_cast<std::uint32_t>(mesh.positions.size());
        mesh.positions.push_back(crossings.roots[i].position);
        mesh.normals.push_back(unit_or_zero(crossings.roots[i].gradient));
        const double norm = glm::length(crossings.roots[i].gradient);
        mesh.gradient_norms.push_back(std::isfinite(norm) ? norm : 0.0);
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
        mesh.gradient_norms.insert(mesh.gradient_norms.end(), part.extra_gradient_norms.begin(),
                                   part.extra_gradient_norms.end());
    }
    return mesh;
}

}  // namespace isomesh
