// locate_crossings: the crossings of many cell edges, bisected in lockstep, are those a plain
// bisection of each edge on its own finds.
#include <gtest/gtest.h>

#include <vector>

#include "polygonize/crossing_vertices.h"
#include "support/mesh_checks.h"

namespace isomesh {
namespace {

/// The reference: bisection of one edge, one value at a time, straight from the evaluator.
CrossingKey bisect(Evaluator& evaluator, const Lattice& lattice, const CellEdge& edge,
                   int finest_depth) {
    glm::u32vec3 lo = edge.lower, hi = edge.lower;
    std::uint32_t span = lattice.span(edge.depth);
    hi[edge.axis] += span;
    const bool lo_inside = is_inside(evaluator.value(lattice.point(lo)));
    while (span > lattice.span(finest_depth)) {
        span /= 2;
        glm::u32vec3 mid = lo;
        mid[edge.axis] += span;
        (is_inside(evaluator.value(lattice.point(mid))) == lo_inside ? lo : hi) = mid;
    }
    return Lattice::edge_key(lo, edge.axis) | std::uint64_t(finest_depth) << 53;
}

TEST(CrossingVertices, locate_crossings_in_lockstep_finds_each_edges_bisection) {
    // A wavy surface, so that edges of coarse cells are crossed at different depths' steps.
    const auto field = test::field_of("x^2+y^2+z^2+0.3sin(5x)cos(4y)=0.8");
    const auto evaluator = field->make_evaluator();
    const Lattice lattice({{-1.0, -1.0, -1.0}, {1.0, 1.0, 1.0}}, kMaxOctreeDepth);
    constexpr int kFinest = 9;
    // Every crossed edge of the cells at depths 3 to 6 along the lattice line y = z = centre-ish,
    // of mixed depths and axes, in one batch.
    std::vector<CellEdge> edges;
    for (int depth = 3; depth <= 6; ++depth) {
        const std::uint32_t cells = 1u << depth;
        for (std::uint32_t i = 0; i < cells; ++i) {
            for (std::uint32_t j = 0; j < cells; j += cells / 4) {
                for (int axis = 0; axis < 3; ++axis) {
                    glm::u32vec3 coords(j, j / 2, i);
                    coords[axis] = i;
                    coords[(axis + 1) % 3] = j;
                    CellEdge edge{lattice.origin({coords, depth}), axis, depth};
                    glm::u32vec3 end = edge.lower;
                    end[axis] += lattice.span(depth);
                    if (is_inside(evaluator->value(lattice.point(edge.lower))) !=
                        is_inside(evaluator->value(lattice.point(end))))
                        edges.push_back(edge);
                }
            }
        }
    }
    ASSERT_GT(edges.size(), 50u);
    CornerCache cache(*evaluator, lattice);
    std::vector<CrossingKey> keys(edges.size());
    locate_crossings(cache, lattice, edges, kFinest, keys);
    for (std::size_t i = 0; i < edges.size(); ++i) {
        EXPECT_EQ(keys[i], bisect(*evaluator, lattice, edges[i], kFinest)) << i;
        EXPECT_EQ(keys[i], locate_crossing(cache, lattice, edges[i], kFinest)) << i;
    }
}

}  // namespace
}  // namespace isomesh
