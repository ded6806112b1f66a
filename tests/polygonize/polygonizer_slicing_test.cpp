// Polygonizer::advance and mesh_slice: the octree and the final mesh made over many short budgets
// are those made at once.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <thread>

#include "polygonize/polygonizer.h"
#include "support/mesh_checks.h"

namespace isomesh {
namespace {

TEST(Polygonizer, mesh_slice_over_many_budgets_gives_the_mesh_of_one_call) {
    for (const char* expression :
         {"x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8=0", "sin(x)cos(y)+sin(y)cos(z)+sin(z)cos(x)=0"}) {
        SCOPED_TRACE(expression);
        const auto field = test::field_of(expression);
        PolygonizeSettings settings;
        settings.box = {{-3.3, -3.3, -3.3}, {3.3, 3.3, 3.3}};
        settings.min_depth = 3;
        settings.max_depth = 7;
        const PolygonizeResult whole = polygonize(*field, settings);

        Polygonizer polygonizer(field, settings);
        polygonizer.advance(WorkBudget{});
        ASSERT_TRUE(polygonizer.complete());
        // A clock that ticks at each look: every budget runs out after one chunk of work.
        auto ticks = std::make_shared<std::int64_t>(0);
        std::optional<PolygonizeResult> sliced;
        int calls = 0;
        for (; !sliced; ++calls) {
            sliced = polygonizer.mesh_slice(WorkBudget(*ticks + 1, [ticks] { return (*ticks)++; }));
            ASSERT_LT(calls, 100000);
        }
        EXPECT_GT(calls, 3);  // one per chunk of work: it was sliced
        test::expect_identical(sliced->mesh, whole.mesh);
        EXPECT_EQ(sliced->stats.cells, whole.stats.cells);
        EXPECT_EQ(sliced->stats.unresolved_cells, whole.stats.unresolved_cells);
    }
}

// The octree classified a few cells per budget (a round's tasks each stop after a family, and
// the cells they left are classified first in the next call) has the frontier of one call.
TEST(Polygonizer, advance_over_many_budgets_gives_the_octree_of_one_call) {
    const auto field = test::field_of("x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8=0");
    PolygonizeSettings settings;
    settings.box = {{-3.3, -3.3, -3.3}, {3.3, 3.3, 3.3}};
    settings.min_depth = 3;
    settings.max_depth = 6;
    settings.threads = 2;
    const PolygonizeResult whole = polygonize(*field, settings);

    Polygonizer polygonizer(field, settings);
    // A clock that ticks at each look (from both workers): each budget lasts a few looks.
    auto ticks = std::make_shared<std::atomic<std::int64_t>>(0);
    int calls = 0;
    for (; !polygonizer.complete(); ++calls) {
        polygonizer.advance(WorkBudget(3, [ticks] { return (*ticks)++; }));
        ASSERT_LT(calls, 100000);
    }
    EXPECT_GT(calls, 100);  // it was sliced, mostly in the middle of rounds
    const PolygonizeResult sliced = polygonizer.mesh(WorkBudget{});
    test::expect_identical(sliced.mesh, whole.mesh);
    EXPECT_EQ(sliced.stats.cells, whole.stats.cells);
    EXPECT_EQ(sliced.stats.unresolved_cells, whole.stats.unresolved_cells);
}

// Where the octree's cell cap binds (apply() counts the cells in octree order), budgets that cut
// one worker's task while the other classifies on still give the octree of one call: the cells
// classified ahead wait for those before them.
TEST(Polygonizer, advance_over_many_budgets_gives_the_octree_of_one_call_where_the_cap_binds) {
    const auto field = test::field_of("x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8=0");
    PolygonizeSettings settings;
    settings.box = {{-3.3, -3.3, -3.3}, {3.3, 3.3, 3.3}};
    settings.min_depth = 3;
    settings.max_depth = 6;
    settings.max_cells = 3000;
    settings.threads = 2;
    Polygonizer whole(field, settings);
    whole.advance(WorkBudget{});
    ASSERT_GT(whole.counts().capped, 0u);  // the cap binds
    const PolygonizeResult expected = whole.mesh(WorkBudget{});

    Polygonizer polygonizer(field, settings);
    // A clock that ticks at each look from the calling thread only (the other worker reads the
    // start, and never runs out): the caller's task stops after a few families while the other
    // worker's tasks run to their end, ahead of it.
    auto ticks = std::make_shared<std::int64_t>(0);
    const std::thread::id caller = std::this_thread::get_id();
    const auto clock = [ticks, caller]() -> std::int64_t {
        return std::this_thread::get_id() == caller ? (*ticks)++ : 0;
    };
    int calls = 0;
    for (; !polygonizer.complete(); ++calls) {
        polygonizer.advance(WorkBudget(5, clock));
        ASSERT_LT(calls, 100000);
    }
    EXPECT_GT(calls, 3);
    EXPECT_EQ(polygonizer.counts().capped, whole.counts().capped);
    const PolygonizeResult sliced = polygonizer.mesh(WorkBudget{});
    test::expect_identical(sliced.mesh, expected.mesh);
    EXPECT_EQ(sliced.stats.cells, expected.stats.cells);
    EXPECT_EQ(sliced.stats.unresolved_cells, expected.stats.unresolved_cells);
}

}  // namespace
}  // namespace isomesh
