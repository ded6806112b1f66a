// A property of function versions (issue 10): whatever sequence of new functions, parameter values
// and constraints a user sends (a slider dragged, an expression retyped, the budget changed, new
// versions arriving before the last one converged), every converged mesh is valid (manifold,
// watertight or cut by the box, facing f > 0, vertices on the surface) and has the topology a
// fresh Pipeline makes of the last function. Random sequences from a fixed seed, across topology
// changes: a hyperboloid through its cone (c through 0), a torus whose hole closes (R below r),
// a sphere splitting into two (a above sqrt(0.3)).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <glm/geometric.hpp>

#include "counting_field.h"
#include "eval/tape_field.h"
#include "expr/compile.h"
#include "mesh/topology.h"
#include "progressive/pipeline.h"
#include "support/mesh_checks.h"

namespace isomesh {
namespace {

/// An expression of one parameter and the values a user gives it, ordered as a slider moves.
struct Family {
    const char* name;
    const char* expression;
    std::vector<double> values;
};

const std::vector<Family>& families() {
    static const std::vector<Family> all = {
        // One sheet (c > 0), two sheets (c < 0); 0 itself is the cone's singular point.
        {"hyperboloid", "x^2+y^2-z^2=c", {1.0, 0.5, 0.2, 0.05, -0.05, -0.2, -0.5, -1.0}},
        // r = 0.5: a torus for R > 0.5, its hole closed (one sphere-like component) below.
        {"torus", "(sqrt(x^2+y^2)-R)^2+z^2=0.25", {1.0, 0.8, 0.65, 0.55, 0.45, 0.4, 0.3}},
        // One component while a^2 < 0.3, two beyond; none for a < -sqrt(0.3).
        {"splitting_sphere", "(x^2-a)^2+y^2+z^2=0.3", {-0.3, 0.0, 0.3, 0.5, 0.6, 0.8, 1.0}},
    };
    return all;
}

const std::vector<std::size_t> kBudgets = {400, 1500, 4000};
/// Boxes of every shape: a cube, a slab (cells that are not cubes, the surface cut by the box
/// near its middle) and a cube off the origin.
const std::vector<Box> kBoxes = {
    {{-2.0, -2.0, -2.0}, {2.0, 2.0, 2.0}},
    {{-2.0, -2.0, -0.7}, {2.0, 2.0, 0.7}},
    {{-1.5, -2.0, -2.0}, {2.5, 2.0, 2.0}},
};

/// The field of family `f` at its `v`-th value: the expression compiled once, bound per value
/// (as the server binds a version's parameters: server/function_version.cpp).
std::shared_ptr<const Field> field_of(std::size_t f, std::size_t v) {
    static std::map<std::size_t, std::shared_ptr<const Tape>> tapes;
    auto& tape = tapes[f];
    if (!tape) {
        CompileResult compiled = compile_expression(families()[f].expression);
        EXPECT_TRUE(compiled.ok());
        EXPECT_EQ(compiled.tape.params.size(), 1u);
        tape = std::make_shared<const Tape>(std::move(compiled.tape));
    }
    return make_tape_field(tape, {families()[f].values[v]});
}

PipelineSettings settings_for(std::size_t budget, const Box& box) {
    PipelineSettings s;
    s.phase1.box = box;
    s.refine.constraint = Constraint::triangle_budget(budget);
    return s;
}

/// Where a sequence stands: the function and the constraint of its last version.
struct State {
    std::size_t family = 0, value = 0, budget = 0, box = 0;
};

std::string describe(const State& s) {
    std::ostringstream out;
    const Family& f = families()[s.family];
    const Box& box = kBoxes[s.box];
    out << f.name << " " << f.expression << " at " << f.values[s.value] << ", budget "
        << kBudgets[s.budget] << ", box [" << box.lo.x << "," << box.hi.x << "]x[" << box.lo.y
        << "," << box.hi.y << "]x[" << box.lo.z << "," << box.hi.z << "]";
    return out.str();
}

/// Triangles whose geometric normal points against grad f at their corners (evaluated afresh,
/// not the mesh's own normals, which a fold would reverse too).
std::size_t triangles_facing_negative_f(const Field& field, const Mesh& mesh) {
    auto evaluator = field.make_evaluator();
    std::size_t inward = 0;
    for (const auto& t : mesh.triangles) {
        const glm::dvec3 geometric =
            glm::normalize(glm::cross(mesh.positions[t[1]] - mesh.positions[t[0]],
                                      mesh.positions[t[2]] - mesh.positions[t[0]]));
        glm::dvec3 mean(0.0);
        for (int k = 0; k < 3; ++k) {
            const glm::dvec3 g = evaluator->value_gradient(mesh.positions[t[k]]).gradient;
            if (glm::length(g) > 0.0) mean += glm::normalize(g);
        }
        inward += glm::dot(geometric, mean) < -0.25 * glm::length(mean);
    }
    return inward;
}

/// A valid mesh of `field` (mesh.h's invariants, boundary only on the box) facing f > 0.
void expect_valid(const Field& field, const Mesh& mesh, const Box& box) {
    test::expect_valid_mesh(field, mesh, box, test::BaseEdges::any);
    EXPECT_EQ(triangles_facing_negative_f(field, mesh), 0u) << "triangles facing f < 0";
}

/// The topology of a fresh pipeline's converged mesh of `s`, made once per state; that mesh is
/// checked too (with its own trace), so that a failure says whether versions or phase 1 caused it.
const TopologyReport& fresh_topology(const State& s) {
    static std::map<std::tuple<std::size_t, std::size_t, std::size_t, std::size_t>, TopologyReport>
        made;
    const auto key = std::make_tuple(s.family, s.value, s.budget, s.box);
    const auto it = made.find(key);
    if (it != made.end()) return it->second;
    const auto field = field_of(s.family, s.value);
    Pipeline fresh(field, settings_for(kBudgets[s.budget], kBoxes[s.box]));
    fresh.run_to_convergence();
    const Mesh mesh = fresh.mesh().mesh;
    SCOPED_TRACE("a fresh pipeline of " + describe(s));
    expect_valid(*field, mesh, kBoxes[s.box]);
    return made[key] = analyze_topology(mesh);
}

/// Steps in slices as the server does (slices of evaluation calls rather than time, so that a
/// seed replays exactly), applying each delta to a client's copy, until converged or `max_steps`
/// steps were made. True when converged.
bool step(Pipeline& pipeline, test::EvaluationCounter& counter, DeltaMesh& client, int max_steps) {
    for (int i = 0; i < max_steps; ++i) {
        const PipelineStep s = pipeline.step(WorkBudget(500, counter.clock()));
        const std::string error = client.apply(s.delta);
        EXPECT_EQ(error, "");
        if (!error.empty()) return false;
        if (s.converged) return true;
    }
    return false;
}

/// Failures recorded so far in this test (gtest records no part for a passing assertion).
int failure_parts() {
    return ::testing::UnitTest::GetInstance()->current_test_info()->result()->total_part_count();
}

/// The property at a converged version; false (after reporting) when it fails.
bool check_converged(const Pipeline& pipeline, const DeltaMesh& client, const State& s) {
    const int parts_before = failure_parts();
    const auto field = field_of(s.family, s.value);
    const Mesh mesh = pipeline.mesh().mesh;
    test::expect_identical(test::without_adjacency(client.to_mesh()),
                           test::without_adjacency(mesh));
    expect_valid(*field, mesh, kBoxes[s.box]);
    const TopologyReport got = analyze_topology(mesh);
    const TopologyReport& fresh = fresh_topology(s);
    EXPECT_EQ(got.components, fresh.components) << "components";
    EXPECT_EQ(got.euler_characteristic, fresh.euler_characteristic) << "Euler characteristic";
    EXPECT_EQ(got.boundary_edges == 0, fresh.boundary_edges == 0) << "closed";
    // The budget is met (within 1: a split adds two triangles), or said to be out of reach
    // with the fewest triangles the topology allows (no split may be refused everywhere).
    const std::size_t budget = kBudgets[s.budget];
    if (pipeline.status().budget_unreachable) {
        EXPECT_GT(pipeline.status().minimum_triangles, budget);
        EXPECT_EQ(mesh.triangle_count(), pipeline.status().minimum_triangles);
    } else if (mesh.triangle_count() > 0) {  // (none: no surface in the box)
        EXPECT_LE(mesh.triangle_count(), budget);
        EXPECT_GE(mesh.triangle_count() + 1, budget) << "converged short of the budget";
    }
    return failure_parts() == parts_before;
}

struct Counts {
    int sequences = 0, updates = 0, checked = 0;
};

/// One random sequence of `length` updates from `seed`; stops at its first failed check.
void run_sequence(std::uint32_t seed, int length, Counts& counts) {
    std::mt19937 rng(seed);
    auto below = [&rng](std::size_t n) {
        return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng);
    };
    State s{below(families().size()), 0, below(kBudgets.size()), below(kBoxes.size())};
    s.value = below(families()[s.family].values.size());
    std::string history = "seed " + std::to_string(seed) + ": start " + describe(s);
    auto counter = std::make_shared<test::EvaluationCounter>();
    const auto counted = [&counter](std::shared_ptr<const Field> field) {
        return std::make_shared<test::CountingField>(std::move(field), counter);
    };
    // A new box makes a new pipeline, whose first delta a client applies to an empty mesh (the
    // server's keyframe: server/session.cpp, start_version).
    const auto fresh_pipeline = [&] {
        return std::make_unique<Pipeline>(counted(field_of(s.family, s.value)),
                                          settings_for(kBudgets[s.budget], kBoxes[s.box]));
    };
    std::unique_ptr<Pipeline> pipeline = fresh_pipeline();
    DeltaMesh client;
    ++counts.sequences;
    for (int u = 0; u <= length; ++u) {
        // Converge (and check) mostly; otherwise the next update comes a few steps in.
        const bool last = u == length;
        const int max_steps = last || below(10) < 7 ? 1'000'000 : 1 + int(below(4));
        SCOPED_TRACE(history);
        const int parts_before = failure_parts();
        const bool converged = step(*pipeline, *counter, client, max_steps);
        if (failure_parts() != parts_before) return;
        if (converged) {
            ++counts.checked;
            if (!check_converged(*pipeline, client, s)) return;
        }
        if (last) break;
        ++counts.updates;
        const std::size_t kind = below(10);
        if (kind < 5) {  // the slider: a neighbouring value, or a jump
            const std::size_t n = families()[s.family].values.size();
            s.value = below(3) == 0 ? below(n) : (s.value + (below(2) ? 1 : n - 1)) % n;
            pipeline->set_field(counted(field_of(s.family, s.value)));
        } else if (kind < 7) {  // another expression typed
            s.family = below(families().size());
            s.value = below(families()[s.family].values.size());
            pipeline->set_field(counted(field_of(s.family, s.value)));
        } else if (kind < 9) {
            s.budget = below(kBudgets.size());
            pipeline->set_constraint(Constraint::triangle_budget(kBudgets[s.budget]));
        } else {
            s.box = below(kBoxes.size());
            pipeline = fresh_pipeline();
            client = DeltaMesh();
        }
        history += (converged ? "" : " (" + std::to_string(max_steps) + " steps, not converged)") +
                   "; then " + describe(s);
    }
}

TEST(PipelineVersions, every_converged_version_is_valid_with_the_fresh_topology) {
    constexpr std::uint32_t kSeed = 20261124;
    constexpr int kSequences = 60, kLength = 8;
    const auto start = std::chrono::steady_clock::now();
    Counts counts;
    for (int i = 0; i < kSequences; ++i) run_sequence(kSeed + i, kLength, counts);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf(
        "versions property: %d sequences, %d updates, %d converged versions checked, "
        "%.1f s\n",
        counts.sequences, counts.updates, counts.checked, seconds);
}

}  // namespace
}  // namespace isomesh
