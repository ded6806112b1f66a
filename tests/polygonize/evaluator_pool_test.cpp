// EvaluatorPool with helpers (polygonize/evaluator_pool.h, work/helpers.h): phase 1's mesh is
// the same whichever helpers ran how many items, and a helper's evaluator is made only once a
// helper takes its slot (a server's session holds none for the cores that never help it).
#include "polygonize/evaluator_pool.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "polygonize/polygonizer.h"
#include "support/mesh_checks.h"

namespace isomesh {
namespace {

/// Starts a thread for each offer it gets, recalled after `items` items; joins them when the
/// offer is withdrawn.
class RecallingHelpers : public Helpers {
  public:
    explicit RecallingHelpers(std::size_t items) : items_(items) {}
    void offer(const std::shared_ptr<HelpOffer>& offer, unsigned threads) override {
        for (unsigned t = 0; t < threads; ++t) {
            threads_.emplace_back([this, offer] {
                std::size_t asked = 0;
                helped += offer->help([&] { return asked++ >= items_; });
            });
        }
    }
    void withdraw(const HelpOffer&) override { threads_.clear(); }
    std::atomic<std::size_t> helped{0};

  private:
    std::size_t items_;
    std::vector<std::jthread> threads_;
};

/// Never helps.
class BusyHelpers : public Helpers {
  public:
    void offer(const std::shared_ptr<HelpOffer>&, unsigned) override {}
    void withdraw(const HelpOffer&) override {}
};

TEST(EvaluatorPool, polygonize_mesh_is_the_same_whatever_the_helpers_ran) {
    const auto field = test::field_of("x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8=0");
    PolygonizeSettings settings;
    settings.box = {{-3.3, -3.3, -3.3}, {3.3, 3.3, 3.3}};
    settings.min_depth = 3;
    settings.max_depth = 7;
    settings.threads = 1;
    const PolygonizeResult alone = polygonize(*field, settings);
    ASSERT_GT(alone.mesh.triangle_count(), 0u);
    for (std::size_t items : {0u, 1u, 5u, 1000000u}) {
        for (int threads : {2, 3}) {
            SCOPED_TRACE(std::to_string(threads) + " threads, recalled after " +
                         std::to_string(items) + " items");
            RecallingHelpers helpers(items);
            settings.threads = threads;
            settings.helpers = &helpers;
            const PolygonizeResult helped = polygonize(*field, settings);
            test::expect_identical(helped.mesh, alone.mesh);
            EXPECT_EQ(helped.stats.cells, alone.stats.cells);
            if (items > 0) {
                EXPECT_GT(helpers.helped, 0u);
            }
        }
    }
}

/// Phase 1 advanced over budgets of `ticks` looks at a shared counter each (helpers read it
/// too), then meshed.
Mesh advanced_in_slices(const std::shared_ptr<const Field>& field,
                        const PolygonizeSettings& settings, std::int64_t ticks) {
    Polygonizer polygonizer(field, settings);
    auto clock = std::make_shared<std::atomic<std::int64_t>>(0);
    for (int calls = 0; !polygonizer.complete(); ++calls) {
        polygonizer.advance(WorkBudget(ticks, [clock] { return (*clock)++; }));
        EXPECT_LT(calls, 1000000);
        if (calls >= 1000000) break;
    }
    return polygonizer.mesh(WorkBudget{}).mesh;
}

TEST(EvaluatorPool, advance_over_short_budgets_gives_the_mesh_whatever_the_helpers_ran) {
    // Budgets cut rounds while helpers classify later cells than the caller: the octree keeps
    // only the cells classified in a row from the first (octree.cpp). (Where out-of-order cells
    // changed the feature search, past its 4,096 cells, bear.vm: tests/clients/server_help_test.)
    const auto field = test::field_of("x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8=0");
    PolygonizeSettings settings;
    settings.box = {{-3.3, -3.3, -3.3}, {3.3, 3.3, 3.3}};
    settings.min_depth = 2;
    settings.max_depth = 4;
    settings.threads = 1;
    const Mesh alone = advanced_in_slices(field, settings, 40);
    ASSERT_GT(alone.triangle_count(), 0u);
    for (int run = 0; run < 5; ++run) {
        RecallingHelpers helpers(1000000);
        settings.threads = 3;
        settings.helpers = &helpers;
        test::expect_identical(advanced_in_slices(field, settings, 40), alone);
    }
}

TEST(EvaluatorPool, for_each_makes_a_helpers_evaluator_only_once_a_helper_takes_its_slot) {
    const auto field = test::field_of("x^2+y^2+z^2=1");
    BusyHelpers busy;
    EvaluatorPool idle_cores(*field, 4, &busy);
    std::vector<int> done(100, 0);
    const auto task = [&](std::size_t i, CountingEvaluator&) { ++done[i]; };
    idle_cores.for_each(done.size(), task);
    EXPECT_EQ(idle_cores.evaluators_made(), 1u);
    EXPECT_EQ(done, std::vector<int>(100, 1));

    RecallingHelpers one_item(1);
    EvaluatorPool helped(*field, 4, &one_item);
    helped.for_each(done.size(), task);
    EXPECT_EQ(helped.evaluators_made(), 1u + one_item.helped);  // each helper ran one item
    EXPECT_EQ(done, std::vector<int>(100, 2));
}

}  // namespace
}  // namespace isomesh
