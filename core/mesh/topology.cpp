// Topology checks and triangle adjacency, by sorting the triangles' half-edges by undirected edge.
#include "mesh/topology.h"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include <glm/geometric.hpp>

namespace isomesh {
namespace {

/// One side of a triangle: the edge from triangles[triangle][side] to the next vertex.
struct HalfEdge {
    std::uint32_t lo = 0, hi = 0;  // the undirected edge's vertices, lo < hi
    std::uint32_t triangle = 0;
    std::uint8_t side = 0;
    bool forward = false;  // runs lo -> hi
};

class DisjointSets {
  public:
    explicit DisjointSets(std::size_t n) {
        parent_.reserve(n);  // (push_back: GCC 12 misreads a sized constructor + iota at -O3)
        for (std::size_t i = 0; i < n; ++i) parent_.push_back(i);
    }
    std::size_t find(std::size_t i) {
        while (parent_[i] != i) i = parent_[i] = parent_[parent_[i]];
        return i;
    }
    void unite(std::size_t a, std::size_t b) {
        a = find(a);
        b = find(b);
        if (a != b) parent_[std::max(a, b)] = std::min(a, b);
    }

  private:
    std::vector<std::size_t> parent_;
};

void check_indices(const Mesh& mesh) {
    if (mesh.positions.empty()) return;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        for (std::uint32_t v : mesh.triangles[t]) {
            if (v >= mesh.positions.size()) {
                throw std::invalid_argument("triangle " + std::to_string(t) + " refers to vertex " +
                                            std::to_string(v) + " of a mesh with " +
                                            std::to_string(mesh.positions.size()) + " vertices");
            }
        }
    }
}

/// The half-edges of all non-collapsed sides (a side whose two ends are the same index is no
/// edge), grouped by undirected edge.
std::vector<HalfEdge> sorted_half_edges(const Mesh& mesh) {
    std::vector<HalfEdge> half_edges;
    half_edges.reserve(3 * mesh.triangles.size());
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        const auto& tri = mesh.triangles[t];
        for (std::uint8_t side = 0; side < 3; ++side) {
            const std::uint32_t a = tri[side], b = tri[(side + 1) % 3];
            if (a == b) continue;
            half_edges.push_back(
                {std::min(a, b), std::max(a, b), static_cast<std::uint32_t>(t), side, a < b});
        }
    }
    std::sort(half_edges.begin(), half_edges.end(), [](const HalfEdge& x, const HalfEdge& y) {
        return std::tie(x.lo, x.hi, x.triangle, x.side) < std::tie(y.lo, y.hi, y.triangle, y.side);
    });
    return half_edges;
}

/// Calls visit(first, count) for each run of half-edges on one undirected edge.
template <typename Visit>
void for_each_edge(const std::vector<HalfEdge>& half_edges, Visit visit) {
    for (std::size_t begin = 0; begin < half_edges.size();) {
        std::size_t end = begin + 1;
        while (end < half_edges.size() && half_edges[end].lo == half_edges[begin].lo &&
               half_edges[end].hi == half_edges[begin].hi) {
            ++end;
        }
        visit(&half_edges[begin], end - begin);
        begin = end;
    }
}

bool is_degenerate(const Mesh& mesh, const std::array<std::uint32_t, 3>& tri) {
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0]) return true;
    if (mesh.positions.empty()) return false;
    const glm::dvec3 p0 = mesh.positions[tri[0]], p1 = mesh.positions[tri[1]],
                     p2 = mesh.positions[tri[2]];
    const double longest =
        std::max({glm::distance(p0, p1), glm::distance(p1, p2), glm::distance(p2, p0)});
    return glm::length(glm::cross(p1 - p0, p2 - p0)) <= 1e-14 * longest * longest;
}

/// Vertices whose incident triangles split into several edge-connected fans. Triangle corners
/// (3 t + k) are joined across every edge incident to the corner's vertex.
std::size_t count_nonmanifold_vertices(const Mesh& mesh, const std::vector<HalfEdge>& half_edges) {
    const auto corner = [&mesh](std::uint32_t t, std::uint32_t v) {
        const auto& tri = mesh.triangles[t];
        const std::size_t k = tri[0] == v ? 0 : (tri[1] == v ? 1 : 2);
        return 3 * static_cast<std::size_t>(t) + k;
    };
    DisjointSets fans(3 * mesh.triangles.size());
    for_each_edge(half_edges, [&](const HalfEdge* e, std::size_t count) {
        for (std::size_t i = 1; i < count; ++i) {
            fans.unite(corner(e[0].triangle, e[0].lo), corner(e[i].triangle, e[i].lo));
            fans.unite(corner(e[0].triangle, e[0].hi), corner(e[i].triangle, e[i].hi));
        }
    });
    std::vector<std::pair<std::uint32_t, std::size_t>> vertex_fans;  // (vertex, fan root)
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        for (std::size_t k = 0; k < 3; ++k) {
            vertex_fans.emplace_back(mesh.triangles[t][k], fans.find(3 * t + k));
        }
    }
    std::sort(vertex_fans.begin(), vertex_fans.end());
    vertex_fans.erase(std::unique(vertex_fans.begin(), vertex_fans.end()), vertex_fans.end());
    std::size_t nonmanifold = 0;
    for (std::size_t i = 1; i < vertex_fans.size(); ++i) {
        const bool second_fan = vertex_fans[i].first == vertex_fans[i - 1].first;
        const bool third_or_more = i >= 2 && vertex_fans[i].first == vertex_fans[i - 2].first;
        if (second_fan && !third_or_more) ++nonmanifold;
    }
    return nonmanifold;
}

}  // namespace

TopologyReport analyze_topology(const Mesh& mesh) {
    check_indices(mesh);
    TopologyReport report;
    report.triangles = mesh.triangles.size();

    std::vector<std::uint32_t> used;
    used.reserve(3 * mesh.triangles.size());
    for (const auto& tri : mesh.triangles) used.insert(used.end(), tri.begin(), tri.end());
    std::sort(used.begin(), used.end());
    used.erase(std::unique(used.begin(), used.end()), used.end());
    report.vertices = used.size();

    const std::vector<HalfEdge> half_edges = sorted_half_edges(mesh);
    DisjointSets components(used.empty() ? 0 : used.back() + std::size_t{1});
    for (const auto& tri : mesh.triangles) {
        components.unite(tri[0], tri[1]);
        components.unite(tri[1], tri[2]);
    }
    for (std::uint32_t v : used) report.components += components.find(v) == v ? 1 : 0;

    for_each_edge(half_edges, [&](const HalfEdge* e, std::size_t count) {
        ++report.edges;
        if (count == 1) ++report.boundary_edges;
        if (count >= 3) ++report.nonmanifold_edges;
        if (count == 2 && e[0].forward == e[1].forward) ++report.inconsistently_oriented_edges;
    });
    report.nonmanifold_vertices = count_nonmanifold_vertices(mesh, half_edges);
    for (const auto& tri : mesh.triangles) {
        report.degenerate_triangles += is_degenerate(mesh, tri) ? 1 : 0;
    }
    report.euler_characteristic = static_cast<long>(report.vertices) -
                                  static_cast<long>(report.edges) +
                                  static_cast<long>(report.triangles);
    return report;
}

double signed_volume(const Mesh& mesh) {
    check_indices(mesh);
    double volume = 0.0;
    for (const auto& t : mesh.triangles) {
        const glm::dvec3& p0 = mesh.positions[t[0]];
        volume += glm::dot(p0, glm::cross(mesh.positions[t[1]], mesh.positions[t[2]]));
    }
    return volume / 6.0;
}

void build_adjacency(Mesh& mesh) {
    if (mesh.positions.empty() && !mesh.triangles.empty()) {
        throw std::invalid_argument("build_adjacency needs vertex positions");
    }
    check_indices(mesh);
    const std::vector<HalfEdge> half_edges = sorted_half_edges(mesh);
    mesh.neighbours.assign(mesh.triangles.size(), {kNoNeighbour, kNoNeighbour, kNoNeighbour});
    for_each_edge(half_edges, [&](const HalfEdge* e, std::size_t count) {
        if (count > 2) {
            throw std::invalid_argument("edge (" + std::to_string(e[0].lo) + ", " +
                                        std::to_string(e[0].hi) + ") has " + std::to_string(count) +
                                        " triangles: not manifold");
        }
        if (count == 2) {
            mesh.neighbours[e[0].triangle][e[0].side] = e[1].triangle;
            mesh.neighbours[e[1].triangle][e[1].side] = e[0].triangle;
        }
    });
    mesh.base_edge.resize(mesh.triangles.size());
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        const auto& tri = mesh.triangles[t];
        const auto key = [&](int side) {
            const std::uint32_t a = tri[side], b = tri[(side + 1) % 3];
            const glm::dvec3 d = mesh.positions[a] - mesh.positions[b];
            // Longer first, then the smaller (lo, hi) vertex pair.
            return std::make_tuple(-glm::dot(d, d), std::min(a, b), std::max(a, b));
        };
        int best = 0;
        for (int side = 1; side < 3; ++side) {
            if (key(side) < key(best)) best = side;
        }
        mesh.base_edge[t] = static_cast<std::uint8_t>(best);
    }
}

}  // namespace isomesh
