// The progressive pipeline (progressive/pipeline.h) as the server drives it: slice by slice, a
// client's copy of the mesh updated by every step's delta.
#include "progressive/pipeline.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "counting_field.h"
#include "mesh/topology.h"
#include "support/mesh_checks.h"
#include "support/shared_data.h"

namespace isomesh {
namespace {

Box box_of(double x0, double x1, double y0, double y1, double z0, double z1) {
    return {{x0, y0, z0}, {x1, y1, z1}};
}
Box cube(double r) {
    return box_of(-r, r, -r, r, -r, r);
}

struct Surface {
    std::string name;
    std::string expression;
    Box box;
};

/// The surfaces of the issue that made the budget a bound (the viewer's examples).
const Surface kTorus{"torus", "(sqrt(x^2+y^2)-2)^2+z^2=0.49",
                     box_of(-3.2, 3.2, -3.2, 3.2, -1.2, 1.2)};
const Surface kTanglecube{"tanglecube", "x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8=0", cube(3)};
const Surface kGyroid{"gyroid", "sin(x)cos(y)+sin(y)cos(z)+sin(z)cos(x)=0", cube(6)};
const Surface kHeart{"heart", "(x^2+2.25y^2+z^2-1)^3-x^2z^3-0.1125y^2z^3=0", cube(1.5)};
const Surface kGenusTwo{"genus_two", "((x^2+y^2)^2-x^2+y^2)^2+z^2=0.01",
                        box_of(-1.4, 1.4, -0.9, 0.9, -0.3, 0.3)};
const Surface kBlobbyCube{"blobby_cube", "sqrt(x^2+y^2+z^2)+2cos(2x)+2cos(2y)+2cos(2z)=20",
                          cube(28)};

PipelineSettings settings_for(const Box& box, std::size_t budget) {
    PipelineSettings s;
    s.phase1.box = box;
    s.refine.constraint = Constraint::triangle_budget(budget);
    return s;
}

/// Steps `pipeline` in slices of `slice_us` until converged, applying every delta to a client's
/// copy; at every step the copy has at most the budget's triangles (or, where the budget cannot be
/// met, the fewest the simplification reached). Returns the client's mesh.
DeltaMesh step_to_convergence(Pipeline& pipeline, std::size_t budget, DeltaMesh client = {},
                              std::int64_t slice_us = 2000) {
    for (int step = 0; step < 200000; ++step) {
        const PipelineStep s = pipeline.step(WorkBudget(slice_us, WorkBudget::thread_cpu_clock()));
        const std::string error = client.apply(s.delta);
        EXPECT_EQ(error, "") << "step " << step;
        if (!error.empty()) break;
        const PipelineStatus& status = pipeline.status();
        const std::size_t cap =
            status.budget_unreachable ? std::max(budget, status.minimum_triangles) : budget;
        EXPECT_LE(client.triangle_count(), cap) << "step " << step;
        EXPECT_EQ(client.triangle_count(), pipeline.stats().triangles) << "step " << step;
        if (s.converged) return client;
    }
    ADD_FAILURE() << "did not converge";
    return client;
}

/// The topology of `surface`'s phase-1 mesh, made once per surface (the blobby cube's phase 1
/// takes tens of seconds).
const TopologyReport& phase1_topology(const Surface& surface, const Field& field) {
    static std::map<std::string, TopologyReport> made;
    const auto it = made.find(surface.name);
    if (it != made.end()) return it->second;
    PolygonizeSettings phase1 = refinement_phase1_settings();
    phase1.box = surface.box;
    return made[surface.name] = analyze_topology(polygonize(field, phase1).mesh);
}

/// At convergence: the budget met within one, or the fewest triangles the topology allowed; a
/// valid mesh with the topology of the phase-1 mesh.
void expect_converged_at_budget(const Surface& surface, const std::shared_ptr<const Field>& field,
                                const Pipeline& pipeline, std::size_t budget) {
    const PipelineStatus& status = pipeline.status();
    const RefinedMesh mesh = pipeline.mesh();
    if (status.budget_unreachable) {
        EXPECT_GT(status.minimum_triangles, budget);
        EXPECT_EQ(mesh.mesh.triangle_count(), status.minimum_triangles);
    } else {
        EXPECT_LE(mesh.mesh.triangle_count(), budget);
        EXPECT_GE(mesh.mesh.triangle_count() + 1, budget);
    }
    test::expect_valid_mesh(*field, mesh.mesh, surface.box, test::BaseEdges::any);
    const TopologyReport& fresh = phase1_topology(surface, *field);
    const TopologyReport got = analyze_topology(mesh.mesh);
    EXPECT_EQ(got.components, fresh.components);
    EXPECT_EQ(got.euler_characteristic, fresh.euler_characteristic);
    EXPECT_EQ(got.boundary_edges == 0, fresh.boundary_edges == 0);
}

struct BudgetCase {
    Surface surface;
    std::size_t budget;
};

void PrintTo(const BudgetCase& c, std::ostream* os) {
    *os << c.surface.name << "_" << c.budget;
}

class PipelineBudget : public ::testing::TestWithParam<BudgetCase> {};

std::vector<BudgetCase> budget_cases() {
    std::vector<BudgetCase> cases;
    for (const Surface& s : {kTorus, kTanglecube, kGyroid, kHeart, kGenusTwo})
        for (std::size_t budget : {100u, 1000u, 20000u}) cases.push_back({s, budget});
    return cases;
}

INSTANTIATE_TEST_SUITE_P(Pipeline, PipelineBudget, ::testing::ValuesIn(budget_cases()));

TEST_P(PipelineBudget, step_bounds_every_frame_and_meets_the_budget) {
    const BudgetCase& c = GetParam();
    const auto field = test::field_of(c.surface.expression);
    Pipeline pipeline(field, settings_for(c.surface.box, c.budget));
    step_to_convergence(pipeline, c.budget);
    expect_converged_at_budget(c.surface, field, pipeline, c.budget);
}

// The blobby cube's phase 1 is the longest of all: one run, then the budget lowered below the
// fewest triangles its 983 components allow (simplified as far as they go, twice) and raised again
// (refined from those coarse roots, where a split easily folds a triangle against the surface).
TEST(PipelineBudgetBlobbyCube, step_bounds_every_frame_and_meets_each_budget) {
    const auto field = test::field_of(kBlobbyCube.expression);
    Pipeline pipeline(field, settings_for(kBlobbyCube.box, 20000));
    DeltaMesh client = step_to_convergence(pipeline, 20000);
    expect_converged_at_budget(kBlobbyCube, field, pipeline, 20000);
    for (std::size_t budget : {1000u, 100u, 20000u}) {
        pipeline.set_constraint(Constraint::triangle_budget(budget));
        client = step_to_convergence(pipeline, budget, std::move(client));
        expect_converged_at_budget(kBlobbyCube, field, pipeline, budget);
    }
}

// A first mesh of any function within the first step's budget: octree cells are classified
// until the budget (here counted in evaluation calls) runs out or the frontier reaches
// first_mesh_cells, then meshed.
TEST(Pipeline, step_makes_a_first_mesh_within_its_budget) {
    const Surface bear{"bear", "@" ISOMESH_SHARED_DIR "/testdata/vm/bear.vm", cube(1)};
    const Surface colonnade{"colonnade", "@" ISOMESH_SHARED_DIR "/testdata/vm/colonnade.vm",
                            cube(1)};
    std::vector<Surface> surfaces = {kBlobbyCube, kTanglecube, kHeart};
    if (test::shared_data_present()) surfaces.insert(surfaces.end(), {bear, colonnade});
    for (const Surface& surface : surfaces) {
        SCOPED_TRACE(surface.name);
        auto counter = std::make_shared<test::EvaluationCounter>();
        const auto field =
            std::make_shared<test::CountingField>(test::field_of(surface.expression), counter);
        const PipelineSettings settings = settings_for(surface.box, 20000);
        Pipeline pipeline(field, settings);
        constexpr std::int64_t kBudget = 2000;  // evaluation calls
        pipeline.step(WorkBudget(kBudget, counter->clock()));
        ASSERT_TRUE(pipeline.started());
        // Classification stops within one group of siblings (8 interval evaluations and their
        // edge surveys) after the budget, or once the frontier reaches first_mesh_cells; meshing
        // then splits the leaves that grading and crack patching need (colonnade's sharp edges:
        // 1,039 leaves for a frontier of 512).
        const PolygonizeStats& first = pipeline.phase1_stats();
        EXPECT_LE(first.cells, settings.first_mesh_cells * 5 / 2);
        EXPECT_GT(first.triangles, 0u);
    }
    if (!test::shared_data_present()) GTEST_SKIP() << "bear and colonnade: " ISOMESH_NO_SHARED_DATA;
}

// Each keyframe (a step whose delta replaces the mesh) shows a phase-1 mesh the client has not
// had: the gyroid's final phase-1 mesh is often its last intermediate one (the pending cells became
// leaves unsplit), and it was sent again, resetting its refinement. (A keyframe's delta carries the
// refinement of its step too, so the meshes are told apart by their phase-1 triangle and vertex
// counts.)
TEST(Pipeline, step_sends_no_keyframe_of_the_mesh_shown) {
    auto counter = std::make_shared<test::EvaluationCounter>();
    const auto field =
        std::make_shared<test::CountingField>(test::field_of(kGyroid.expression), counter);
    PipelineSettings settings = settings_for(kGyroid.box, 100000);
    settings.min_intermediate_interval = 0;  // every doubling meshed
    Pipeline pipeline(field, settings);
    DeltaMesh client;
    std::optional<PolygonizeStats> shown;
    for (int step = 0; step < 100000; ++step) {
        const PipelineStep s = pipeline.step(WorkBudget(300, counter->clock()));
        ASSERT_EQ(client.apply(s.delta), "");
        if (s.restarted) {
            const PolygonizeStats& now = pipeline.phase1_stats();
            if (shown) {
                EXPECT_FALSE(now.triangles == shown->triangles && now.vertices == shown->vertices)
                    << "step " << step << ": the phase-1 mesh of " << now.triangles
                    << " triangles again";
            }
            shown = now;
        }
        if (s.converged) break;
    }
    EXPECT_GE(pipeline.status().phase1_meshes, 3u);
    EXPECT_FALSE(pipeline.status().resolving);
}

// Intermediate phase-1 meshes (keyframes of the whole mesh) are spaced by the work between
// them: a phase 1 done within min_intermediate_interval shows its first mesh and its final one.
TEST(Pipeline, step_spaces_intermediate_meshes_by_their_interval) {
    constexpr std::int64_t kNever = std::numeric_limits<std::int64_t>::max();
    for (const std::int64_t interval : {std::int64_t{0}, std::int64_t{3'000}, kNever}) {
        SCOPED_TRACE(interval);
        auto counter = std::make_shared<test::EvaluationCounter>();
        const auto field =
            std::make_shared<test::CountingField>(test::field_of(kGyroid.expression), counter);
        PipelineSettings settings = settings_for(kGyroid.box, 100000);
        settings.min_intermediate_interval = interval;
        Pipeline pipeline(field, settings);
        std::vector<std::int64_t> at;  // evaluation calls at each phase-1 mesh
        for (int step = 0; step < 100000; ++step) {
            const std::size_t meshes = pipeline.status().phase1_meshes;
            const PipelineStep s = pipeline.step(WorkBudget(300, counter->clock()));
            if (pipeline.status().phase1_meshes > meshes) at.push_back(counter->calls.load());
            if (s.converged) break;
        }
        ASSERT_FALSE(pipeline.status().resolving);
        if (interval == kNever) {
            EXPECT_EQ(pipeline.status().phase1_meshes, 2u) << "the first and the final";
            continue;
        }
        EXPECT_GE(at.size(), 3u);  // an intermediate one: its phase 1 classifies for ~20,000 calls
        for (std::size_t i = 1; i + 1 < at.size(); ++i)  // the final mesh comes when it is ready
            EXPECT_GE(at[i] - at[i - 1], interval) << "mesh " << i;
    }
}

// An intermediate mesh is of the frontier coarsened to max_preview_cells (its cost bounded
// whatever the octree holds): shallower than the octree, its merged cells meshed unclassified
// (grading and crack patching may split a few of them again); the final one is of the whole
// frontier.
TEST(Pipeline, step_makes_intermediate_meshes_of_the_coarsened_frontier) {
    constexpr std::size_t kPreviewCells = 500;
    auto counter = std::make_shared<test::EvaluationCounter>();
    const auto field =
        std::make_shared<test::CountingField>(test::field_of(kGyroid.expression), counter);
    PipelineSettings settings = settings_for(kGyroid.box, 100000);
    settings.min_intermediate_interval = 0;  // every doubling meshed
    settings.max_preview_cells = kPreviewCells;
    Pipeline pipeline(field, settings);
    // Uncapped, this run's intermediate meshes have 4,000 to 6,000 cells at depth 5, as the final.
    std::size_t intermediate = 0;
    for (int step = 0; step < 100000; ++step) {
        const std::size_t meshes = pipeline.status().phase1_meshes;
        const PipelineStep s = pipeline.step(WorkBudget(300, counter->clock()));
        if (meshes > 0 && pipeline.status().phase1_meshes > meshes && pipeline.status().resolving) {
            const PolygonizeStats& stats = pipeline.phase1_stats();
            EXPECT_LE(stats.cells, 2 * kPreviewCells) << "step " << step;
            EXPECT_GT(stats.pending_cells, 0u);
            EXPECT_LT(stats.depth, 5);
            ++intermediate;
        }
        if (s.converged) break;
    }
    ASSERT_FALSE(pipeline.status().resolving);
    EXPECT_GE(intermediate, 1u);
    EXPECT_EQ(pipeline.phase1_stats().depth, 5);  // the final mesh: the whole frontier
    EXPECT_GT(pipeline.phase1_stats().cells, 2 * kPreviewCells);
}

// Regions where the equation holds are no surface: said within the first steps (at once where the
// first cells' enclosures are exactly zero; x = x needs a few levels), with an empty mesh.
TEST(Pipeline, step_recognises_regions_where_the_equation_holds) {
    for (const char* expression :
         {"floor(x)=0", "min(x,0)=0", "max(x^2+y^2+z^2-1,0)=0", "0", "x=x"}) {
        SCOPED_TRACE(expression);
        auto counter = std::make_shared<test::EvaluationCounter>();
        const auto field =
            std::make_shared<test::CountingField>(test::field_of(expression), counter);
        Pipeline pipeline(field, settings_for(cube(2), 20000));
        int steps = 1;
        while (!pipeline.step(WorkBudget(10000, WorkBudget::thread_cpu_clock())).converged &&
               steps < 10) {
            ++steps;
        }
        EXPECT_LE(steps, 3);
        EXPECT_TRUE(pipeline.status().region);
        EXPECT_EQ(pipeline.stats().triangles, 0u);
        EXPECT_LT(counter->calls.load(), 20000);  // milliseconds of work, no growth
    }
}

// Cancellation (a new version, a close, a shutdown) is honoured in every loop: whenever it is
// raised, the step returns within a few evaluation calls (the unit of work is one cell's
// classification, whose edge root counting bisects the cell's twelve edges: tens of calls).
TEST(Pipeline, step_honours_cancellation_in_every_loop) {
    const auto inner = test::field_of("x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8=0");
    // The whole run's evaluation calls, to place cancellations all along it.
    auto probe = std::make_shared<test::EvaluationCounter>();
    {
        Pipeline pipeline(std::make_shared<test::CountingField>(inner, probe),
                          settings_for(cube(3), 20000));
        pipeline.run_to_convergence();
    }
    const std::int64_t total = probe->calls.load();
    ASSERT_GT(total, 1000);
    std::int64_t worst = 0;
    for (int k = 1; k <= 40; ++k) {
        auto counter = std::make_shared<test::EvaluationCounter>();
        counter->cancel_at = total * k / 41;
        Pipeline pipeline(std::make_shared<test::CountingField>(inner, counter),
                          settings_for(cube(3), 20000));
        for (int step = 0; step < 100000; ++step) {
            const PipelineStep s = pipeline.step(WorkBudget(&counter->cancel));
            if (s.converged || s.cancelled) break;
        }
        ASSERT_TRUE(counter->cancel.load()) << "cancel at " << counter->cancel_at;
        worst = std::max(worst, counter->calls.load() - counter->calls_when_cancelled.load());
    }
    std::printf("most evaluation calls after a cancellation: %lld\n",
                static_cast<long long>(worst));
    EXPECT_LE(worst, 96);
}

/// The converged mesh of a new pipeline for `field`.
Mesh fresh_mesh(const std::shared_ptr<const Field>& field, const PipelineSettings& settings) {
    Pipeline fresh(field, settings);
    fresh.run_to_convergence();
    return fresh.mesh().mesh;
}

// A new version with the same topology first moves the mesh onto the new surface (the frames
// right after set_field move vertices, no replacement); one that changes the topology replaces it
// with the new function's phase-1 mesh. Either way the version converges to the mesh a new
// pipeline makes of it: the final mesh does not depend on the history.
TEST(Pipeline, set_field_moves_or_replaces_and_converges_to_the_fresh_mesh) {
    const auto sphere = [](double a) { return test::field_of("x^2+y^2+z^2=" + std::to_string(a)); };
    const PipelineSettings settings = settings_for(cube(3), 3000);
    Pipeline pipeline(sphere(4.0), settings);
    DeltaMesh client = step_to_convergence(pipeline, 3000);
    pipeline.set_field(sphere(5.0));
    const PipelineStep moved = pipeline.step(WorkBudget{});
    EXPECT_FALSE(moved.restarted);
    EXPECT_FALSE(moved.delta.moved_vertices.empty());
    EXPECT_EQ(client.apply(moved.delta), "");
    client = step_to_convergence(pipeline, 3000, std::move(client));
    test::expect_valid_mesh(*sphere(5.0), pipeline.mesh().mesh, cube(3), test::BaseEdges::any);
    test::expect_identical(test::without_adjacency(pipeline.mesh().mesh),
                           test::without_adjacency(fresh_mesh(sphere(5.0), settings)));
    test::expect_identical(test::without_adjacency(client.to_mesh()),
                           test::without_adjacency(pipeline.mesh().mesh));

    // Two spheres merging into one: the topology changes, the mesh is replaced.
    const auto pair = [](double d) {
        return test::field_of("min((x-" + std::to_string(d) + ")^2+y^2+z^2,(x+" +
                              std::to_string(d) + ")^2+y^2+z^2)=1");
    };
    Pipeline two(pair(1.5), settings);
    client = step_to_convergence(two, 3000);
    EXPECT_EQ(analyze_topology(two.mesh().mesh).components, 2u);
    two.set_field(pair(0.5));
    client = step_to_convergence(two, 3000, std::move(client));
    EXPECT_EQ(analyze_topology(two.mesh().mesh).components, 1u);
    test::expect_valid_mesh(*pair(0.5), two.mesh().mesh, cube(3), test::BaseEdges::any);
    test::expect_identical(test::without_adjacency(two.mesh().mesh),
                           test::without_adjacency(fresh_mesh(pair(0.5), settings)));
}

// A slider's new value: the first step moves every vertex and ends there, so that the moved mesh
// leaves at once; phase 1 of the new function and the errors' refresh come in later steps.
TEST(Pipeline, set_field_first_step_moves_every_vertex_and_ends_there) {
    const auto sphere = [](double a) { return test::field_of("x^2+y^2+z^2=" + std::to_string(a)); };
    Pipeline pipeline(sphere(4.0), settings_for(cube(3), 3000));
    step_to_convergence(pipeline, 3000);
    const std::size_t vertices = pipeline.mesh().vertex_ids.size();
    pipeline.set_field(sphere(4.5));
    EXPECT_TRUE(pipeline.field_change_pending());
    const PipelineStep moved = pipeline.step(WorkBudget{});
    EXPECT_FALSE(pipeline.field_change_pending());
    EXPECT_EQ(moved.delta.moved_vertices.size(), vertices);
    EXPECT_TRUE(moved.delta.added_triangles.empty());
    EXPECT_TRUE(pipeline.status().resolving) << "phase 1 of the new function waits";
    EXPECT_FALSE(moved.converged);
}

TEST(Pipeline, set_field_beyond_the_vertices_reach_never_shows_them_off_the_new_surface) {
    // A slider jumped from a = 1 to 21 (20 updates coalesced): the radius goes from 1 to 4.6, out
    // of the moving vertices' reach. Once field_change_pending() is false (a server sends the
    // mesh), the mesh is on the new sphere: the new function's first mesh, not the unmoved one.
    const auto sphere = [](int a) { return test::field_of("x^2+y^2+z^2=" + std::to_string(a)); };
    Pipeline pipeline(sphere(1), settings_for(cube(5), 6000));
    step_to_convergence(pipeline, 6000);
    pipeline.set_field(sphere(21));
    for (int step = 0; step < 100 && pipeline.field_change_pending(); ++step)
        pipeline.step(WorkBudget(2000, WorkBudget::thread_cpu_clock()));
    ASSERT_FALSE(pipeline.field_change_pending());
    const Mesh mesh = pipeline.mesh().mesh;
    ASSERT_GT(mesh.triangle_count(), 0u) << "the new surface's first mesh, not an empty one";
    for (const glm::dvec3& p : mesh.positions)
        ASSERT_NEAR(glm::length(p), std::sqrt(21.0), 1e-2) << "a vertex off the new sphere";
}

}  // namespace
}  // namespace isomesh
