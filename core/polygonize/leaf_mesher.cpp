// Leaf meshing with crack patching (see leaf_mesher.h).
#include "polygonize/leaf_mesher.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include <glm/geometric.hpp>

#include "polygonize/mc33.h"
#include "polygonize/vertex_projection.h"

namespace isomesh {

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

namespace {

using Polygon = std::vector<VertexRef>;

/// Vertices the leaf mesher places stay this fraction of the leaf's size away from its faces.
constexpr double kFaceMargin = 0.05;

double gradient_norm(const glm::dvec3& g) {
    const double length = glm::length(g);
    return std::isfinite(length) ? length : 0.0;
}

glm::dvec3 unit_or_zero(const glm::dvec3& v) {
    const double length = glm::length(v);
    return length > 0.0 && std::isfinite(length) ? v / length : glm::dvec3(0.0);
}

/// Face id 2 * axis + side of the cell's faces.
int face_id(int axis, int side) {
    return 2 * axis + side;
}

/// The two faces containing MC33 edge e (mc33.h: edges 4a..4a+3 run along axis a, at offsets
/// (e & 1, (e >> 1) & 1) on the other two axes in increasing order).
std::array<int, 2> faces_of_edge(int e) {
    const int axis = e / 4;
    const int u = axis == 0 ? 1 : 0, v = axis == 2 ? 1 : 2;
    return {face_id(u, e & 1), face_id(v, (e >> 1) & 1)};
}

/// The face two MC33 edges share, or -1.
int common_face(int e0, int e1) {
    for (int f0 : faces_of_edge(e0)) {
        for (int f1 : faces_of_edge(e1)) {
            if (f0 == f1) return f0;
        }
    }
    return -1;
}

bool on_boundary(const glm::dvec3& p, const Box& box) {
    for (int axis = 0; axis < 3; ++axis) {
        if (p[axis] == box.lo[axis] || p[axis] == box.hi[axis]) return true;
    }
    return false;
}

/// The face holding all three corners of a triangle of edge vertices, or -1.
int face_of_triangle(const std::array<std::uint8_t, 3>& ids) {
    for (std::uint8_t id : ids) {
        if (id == kInteriorVertex) return -1;
    }
    const int f = common_face(ids[0], ids[1]);
    return f >= 0 && common_face(ids[1], ids[2]) == f && common_face(ids[2], ids[0]) == f ? f : -1;
}

/// Whether the corners of face (axis, side) of `cell` are not all on one side.
bool face_is_crossed(const LeafMeshingInput& input, const CellId& cell, int axis, int side) {
    int inside = 0;
    for (int c = 0; c < 8; ++c) {
        if (((c >> axis) & 1) != side) continue;
        inside += is_inside(input.values.at(Lattice::key(input.lattice.corner(cell, c))));
    }
    return inside != 0 && inside != 4;
}

/// The marching squares segments of the finer leaves covering one face of a leaf, as a graph
/// between crossings, with the paths along it.
class FaceGraph {
  public:
    void add_segment(VertexRef a, VertexRef b) {
        const int s = static_cast<int>(segments_.size());
        segments_.push_back({a, b});
        used_.push_back(false);
        incident_[a].push_back(s);
        incident_[b].push_back(s);
    }

    /// The vertices strictly between `from` and `to` on the polyline joining them, marking its
    /// segments used; nothing when no unused polyline joins them.
    std::optional<Polygon> walk(VertexRef from, VertexRef to) {
        Polygon inner;
        VertexRef current = from;
        int previous = -1;
        for (std::size_t step = 0; step < segments_.size(); ++step) {
            const auto it = incident_.find(current);
            if (it == incident_.end()) return std::nullopt;
            const std::vector<int>& around = it->second;
            if (around.size() != (current == from ? 1u : 2u)) return std::nullopt;
            const int s = around[0] == previous ? around.back() : around[0];
            if (s == previous || used_[s]) return std::nullopt;
            used_[s] = true;
            current = segments_[s].first == current ? segments_[s].second : segments_[s].first;
            if (current == to) return inner;
            inner.push_back(current);
            previous = s;
        }
        return std::nullopt;
    }

    bool empty() const { return segments_.empty(); }
    /// The surface crosses the face where the finer side is more than one level deeper: the
    /// leaf must be split (grading the octree along the surface, so that each polyline has at
    /// most a few segments and the fans patching it stay close to the surface).
    void mark_unbalanced() { unbalanced_ = true; }
    bool unbalanced() const { return unbalanced_; }

    bool all_used() const {
        return std::all_of(used_.begin(), used_.end(), [](bool u) { return u; });
    }

  private:
    std::vector<std::pair<VertexRef, VertexRef>> segments_;
    std::vector<bool> used_;
    std::unordered_map<VertexRef, std::vector<int>> incident_;
    bool unbalanced_ = false;
};

class LeafMesher {
  public:
    LeafMesher(Evaluator& evaluator, const LeafMeshingInput& input, const CellId& leaf,
               LeafMeshes& out, AncestorPath* path)
        : evaluator_(evaluator), path_(path), in_(input), leaf_(leaf), out_(out) {}

    void run() {
        const std::array<double, 8> values = corner_values(leaf_);
        const CellTriangulation tri = triangulate_cell(finite_values(values));
        std::array<VertexRef, 13> refs{};
        for (int e = 0; e < 12; ++e) {
            const auto [c0, c1] = kEdgeCorners[e];
            if (is_inside(values[c0]) != is_inside(values[c1])) refs[e] = crossing(leaf_, c0, c1);
        }
        // A leaf without triangles still checks its faces: the surface may cross them finely.
        std::array<std::optional<FaceGraph>, 6> faces;
        for (int f = 0; f < 6; ++f) {
            faces[f] = finer_face(f / 2, f % 2);
            if (faces[f] && faces[f]->unbalanced()) return unmatched();
        }
        // Vertices first go to a scratch list, so that an unmatched leaf leaves nothing behind.
        if (tri.uses_interior_vertex()) refs[kInteriorVertex] = interior_vertex(tri, refs);
        for (int t = 0; t < tri.triangle_count; ++t) {
            if (!emit(tri.triangles[t], refs, faces)) return unmatched();
        }
        for (const auto& face : faces) {
            if (face && !face->all_used()) return unmatched();
        }
        const auto offset = static_cast<VertexRef>(out_.extra_positions.size());
        for (auto triangle : triangles_) {
            for (VertexRef& v : triangle) {
                if (v & kExtraVertex) v += offset;
            }
            out_.triangles.push_back(triangle);
        }
        out_.extra_positions.insert(out_.extra_positions.end(), extra_positions_.begin(),
                                    extra_positions_.end());
        out_.extra_normals.insert(out_.extra_normals.end(), extra_normals_.begin(),
                                  extra_normals_.end());
        out_.extra_gradient_norms.insert(out_.extra_gradient_norms.end(),
                                         extra_gradient_norms_.begin(),
                                         extra_gradient_norms_.end());
    }

  private:
    std::array<double, 8> corner_values(const CellId& cell) const {
        std::array<double, 8> values;
        for (int c = 0; c < 8; ++c) {
            values[c] = in_.values.at(Lattice::key(in_.lattice.corner(cell, c)));
        }
        return values;
    }

    /// The crossing on the edge of `cell` from corner c0 to corner c1 (c0 the lower).
    VertexRef crossing(const CellId& cell, int c0, int c1) const {
        const glm::u32vec3 lower = in_.lattice.corner(cell, c0);
        const glm::u32vec3 upper = in_.lattice.corner(cell, c1);
        int axis = 0;
        while (lower[axis] == upper[axis]) ++axis;
        return in_.crossings.at(cell_edge_key(lower, axis, cell.depth));
    }

    /// The segments of the finer leaves across face (axis, side), or nothing when the leaf on
    /// the other side is not finer.
    std::optional<FaceGraph> finer_face(int axis, int side) const {
        const std::vector<CellId> finer = in_.index.finer_across(leaf_, axis, side);
        if (finer.empty()) return std::nullopt;
        FaceGraph graph;
        int deepest = leaf_.depth;
        for (const CellId& cell : finer) {
            add_face_segments(graph, cell, axis, 1 - side);
            deepest = std::max(deepest, cell.depth);
        }
        if (deepest > leaf_.depth + 1 && !graph.empty()) graph.mark_unbalanced();
        return graph;
    }

    /// Marching squares on face (axis, side) of `cell`, as MC33 cuts it.
    void add_face_segments(FaceGraph& graph, const CellId& cell, int axis, int side) const {
        const int u = axis == 0 ? 1 : 0, v = axis == 2 ? 1 : 2;
        // The face's corners in cyclic order.
        std::array<int, 4> corners;
        const int offsets[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
        for (int i = 0; i < 4; ++i) {
            corners[i] = side << axis | offsets[i][0] << u | offsets[i][1] << v;
        }
        const std::array<double, 8> values = finite_values(corner_values(cell));
        std::array<VertexRef, 4> cut{};  // cut[i]: crossing between corners i and i + 1
        std::vector<VertexRef> cuts;
        for (int i = 0; i < 4; ++i) {
            const int a = corners[i], b = corners[(i + 1) % 4];
            if (is_inside(values[a]) == is_inside(values[b])) continue;
            cut[i] = crossing(cell, std::min(a, b), std::max(a, b));
            cuts.push_back(cut[i]);
        }
        if (cuts.size() == 2) {
            graph.add_segment(cuts[0], cuts[1]);
        } else if (cuts.size() == 4) {
            const bool joined = face_joins_inside(values[corners[0]], values[corners[1]],
                                                  values[corners[2]], values[corners[3]]);
            // Joined inside corners cut off the outside ones, and the other way round.
            if (is_inside(values[corners[0]]) == joined) {
                graph.add_segment(cut[0], cut[1]);  // around corners 1 and 3
                graph.add_segment(cut[2], cut[3]);
            } else {
                graph.add_segment(cut[3], cut[0]);  // around corners 0 and 2
                graph.add_segment(cut[1], cut[2]);
            }
        }
    }

    glm::dvec3 approximate(VertexRef v) const {
        if (v & kExtraVertex) return extra_positions_[v & ~kExtraVertex];
        return approximate_crossing(in_.values, in_.lattice, v);
    }

    /// A new vertex on the surface near the mean of `around`, inside the leaf; nothing when the
    /// projection fails.
    std::optional<VertexRef> surface_vertex(const Polygon& around) {
        glm::dvec3 sum(0.0);
        for (VertexRef v : around) sum += approximate(v);
        // Kept off the leaf's faces: a vertex on a face would fan triangles flat onto it.
        Box inner = in_.lattice.cell_box(leaf_);
        const glm::dvec3 margin = kFaceMargin * inner.size();
        inner = {inner.lo + margin, inner.hi - margin};
        if (path_ != nullptr) {
            path_->walk_to(leaf_.depth > 0 ? leaf_.parent() : leaf_);
            path_ = nullptr;  // once per leaf
        }
        const SurfacePoint point = project_to_surface(
            evaluator_, glm::clamp(sum / static_cast<double>(around.size()), inner.lo, inner.hi),
            inner);
        // A point stopped by the margin is not where the surface is: no vertex.
        if (!point.on_surface || on_boundary(point.position, inner)) return std::nullopt;
        extra_positions_.push_back(point.position);
        extra_normals_.push_back(unit_or_zero(point.gradient));
        extra_gradient_norms_.push_back(gradient_norm(point.gradient));
        return kExtraVertex | (extra_positions_.size() - 1);
    }

    /// MC33's interior vertex: on the surface near the mean of the crossings of the loop it fans.
    /// If the projection fails, one of the loop's crossings takes its place (the fan triangles
    /// through that crossing vanish, leaving a fan triangulation of the loop).
    VertexRef interior_vertex(const CellTriangulation& tri, const std::array<VertexRef, 13>& refs) {
        Polygon loop;
        for (int e = 0; e < 12; ++e) {
            if ((tri.interior_vertex_edges >> e) & 1u) loop.push_back(refs[e]);
        }
        return surface_vertex(loop).value_or(loop.front());
    }

    /// Adds the triangle, patched along its edges on finer faces. False when a patch fails.
    bool emit(const std::array<std::uint8_t, 3>& ids, const std::array<VertexRef, 13>& refs,
              std::array<std::optional<FaceGraph>, 6>& faces) {
        // A triangle lying in a face (MC33 joins three crossings of one ambiguous face in a few
        // subcases) cannot be patched into a fan that stays off that face.
        if (const int f = face_of_triangle(ids); f >= 0 && faces[f]) return false;
        Polygon outline;
        bool patched = false;
        for (int i = 0; i < 3; ++i) {
            const std::uint8_t a = ids[i], b = ids[(i + 1) % 3];
            outline.push_back(refs[a]);
            if (a == kInteriorVertex || b == kInteriorVertex) continue;
            const int f = common_face(a, b);
            if (f < 0 || !faces[f]) continue;
            const std::optional<Polygon> inner = faces[f]->walk(refs[a], refs[b]);
            if (!inner) return false;
            if (inner->empty()) continue;
            outline.insert(outline.end(), inner->begin(), inner->end());
            patched = true;
        }
        if (!patched) {
            add_triangle(outline[0], outline[1], outline[2]);
            return true;
        }
        // Fan from a new vertex on the surface inside the leaf (a fan from the opposite corner
        // folds where the polyline bends towards it, and lays triangles flat on the face when
        // two edges are patched). Without such a vertex the leaf is split.
        const std::optional<VertexRef> centre = surface_vertex(outline);
        if (!centre) return false;
        // Where the surface runs nearly along the face, a fan can come out upside down: then too
        // the leaf is split, until its neighbours are no finer there.
        const glm::dvec3 c = approximate(*centre);
        const glm::dvec3 normal = extra_normals_[*centre & ~kExtraVertex];
        for (std::size_t j = 0; j < outline.size(); ++j) {
            const VertexRef a = outline[j], b = outline[(j + 1) % outline.size()];
            if (!(glm::dot(glm::cross(approximate(a) - c, approximate(b) - c), normal) > 0.0)) {
                return false;
            }
            add_triangle(a, b, *centre);
        }
        return true;
    }

    void add_triangle(VertexRef a, VertexRef b, VertexRef c) {
        if (a == b || b == c || c == a) return;  // a fan around a fallback vertex
        triangles_.push_back({a, b, c});
    }

    void unmatched() { out_.unmatched.push_back(leaf_); }

    Evaluator& evaluator_;
    AncestorPath* path_;  // walked to the leaf's parent before the first projection, or null
    const LeafMeshingInput& in_;
    CellId leaf_;
    LeafMeshes& out_;
    std::vector<std::array<VertexRef, 3>> triangles_;
    std::vector<glm::dvec3> extra_positions_;
    std::vector<glm::dvec3> extra_normals_;
    std::vector<double> extra_gradient_norms_;
};

}  // namespace

bool needs_grading(const LeafMeshingInput& input, const CellId& leaf) {
    for (int axis = 0; axis < 3; ++axis) {
        for (int side = 0; side < 2; ++side) {
            for (const CellId& cell : input.index.finer_across(leaf, axis, side)) {
                if (cell.depth > leaf.depth + 1 && face_is_crossed(input, cell, axis, 1 - side)) {
                    return true;
                }
            }
        }
    }
    return false;
}

void mesh_leaf(Evaluator& evaluator, const LeafMeshingInput& input, const CellId& leaf,
               LeafMeshes& out, AncestorPath* path) {
    LeafMesher(evaluator, input, leaf, out, path).run();
}

}  // namespace isomesh
