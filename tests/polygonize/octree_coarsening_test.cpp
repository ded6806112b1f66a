// coarsened (octree.h): the frontier of a preview, its deepest cells merged into their parents,
// covers what the octree's frontier covers with fewer cells; Polygonizer::mesh_slice meshes it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <vector>

#include "polygonize/evaluator_pool.h"
#include "polygonize/octree.h"
#include "polygonize/polygonizer.h"
#include "support/mesh_checks.h"

namespace isomesh {
namespace {

const char* const kTanglecube = "x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8=0";
const Box kBox{{-3.3, -3.3, -3.3}, {3.3, 3.3, 3.3}};

int deepest(const std::vector<FrontierCell>& cells) {
    int depth = 0;
    for (const FrontierCell& f : cells) depth = std::max(depth, f.cell.depth);
    return depth;
}

bool is_ancestor_or_self(const CellId& ancestor, const CellId& cell) {
    return ancestor.depth <= cell.depth && cell.ancestor(ancestor.depth) == ancestor;
}

TEST(Octree, coarsened_merges_the_deepest_cells_into_pending_parents) {
    const auto field = test::field_of(kTanglecube);
    const Lattice lattice(kBox, kMaxOctreeDepth);
    OctreeSettings settings;
    settings.min_depth = 3;
    settings.max_depth = 6;
    Octree octree(lattice, settings);
    EvaluatorPool pool(*field, 1);
    ValueMap values;
    octree.advance(pool, values, WorkBudget{});
    ASSERT_TRUE(octree.complete());
    const std::vector<FrontierCell> frontier = octree.frontier();
    ASSERT_GT(frontier.size(), 1000u);

    EXPECT_EQ(coarsened(frontier, frontier.size()).size(), frontier.size());  // nothing to do
    const std::size_t cap = frontier.size() / 4;
    const std::vector<FrontierCell> coarse = coarsened(frontier, cap);
    EXPECT_LE(coarse.size(), cap);
    EXPECT_LT(deepest(coarse), deepest(frontier));
    for (std::size_t i = 1; i < coarse.size(); ++i)
        ASSERT_LT(lattice.octree_order(coarse[i - 1].cell), lattice.octree_order(coarse[i].cell));
    // Each cell of the frontier lies in exactly one coarse cell, which is the cell itself (its
    // state kept) or a pending ancestor; and each coarse cell holds some cell of the frontier.
    std::vector<int> holds(coarse.size(), 0);
    for (const FrontierCell& f : frontier) {
        int inside = 0;
        for (std::size_t i = 0; i < coarse.size(); ++i) {
            if (!is_ancestor_or_self(coarse[i].cell, f.cell)) continue;
            ++inside;
            ++holds[i];
            if (coarse[i].cell == f.cell) {
                EXPECT_EQ(coarse[i].state, f.state);
            } else {
                EXPECT_EQ(coarse[i].state, CellState::Pending);
            }
        }
        ASSERT_EQ(inside, 1);
    }
    EXPECT_EQ(std::count(holds.begin(), holds.end(), 0), 0);
}

TEST(Polygonizer, mesh_slice_with_max_cells_meshes_the_coarsened_frontier) {
    const auto field = test::field_of(kTanglecube);
    PolygonizeSettings settings;
    settings.box = kBox;
    settings.min_depth = 3;
    settings.max_depth = 7;
    Polygonizer polygonizer(field, settings);
    polygonizer.advance(WorkBudget{});
    ASSERT_TRUE(polygonizer.complete());
    const PolygonizeResult whole = polygonizer.mesh(WorkBudget{});
    const std::optional<PolygonizeResult> preview = polygonizer.mesh_slice(WorkBudget{}, 2000);
    ASSERT_TRUE(preview.has_value());
    // Grading and crack patching may split a few of the coarse cells again.
    EXPECT_LT(preview->stats.cells, whole.stats.cells / 2);
    EXPECT_LT(preview->stats.depth, whole.stats.depth);
    EXPECT_GT(preview->stats.pending_cells, 0u);  // the merged parents, meshed unclassified
    test::expect_valid_mesh(*field, preview->mesh, settings.box);
    // The whole frontier again, bit for bit: the preview changed nothing the octree keeps.
    test::expect_identical(polygonizer.mesh(WorkBudget{}).mesh, whole.mesh);
}

}  // namespace
}  // namespace isomesh
