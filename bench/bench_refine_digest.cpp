// The refiner's output in a few hashes, to show that a change meant to be faster changes nothing:
// build it before and after, run both, compare the lines (`diff`). For each surface and phase-1
// thread count, one hash (FNV-1a, 64 bits) of every delta of a scripted refinement, taken in steps
// of 1,000 operations (splits up to the phase-1 mesh's triangles plus 40,000, merges down to it
// plus 10,000, splits up to it plus 30,000, then a parameter change re-converged), with the
// distance and the epsilon4 measures, and one hash of the final mesh. Not a benchmark: it prints no
// times.
//
//   build/bin/bench_refine_digest > after.txt && diff before.txt after.txt
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "eval/tape_field.h"
#include "expr/compile.h"
#include "expr/parameters.h"
#include "polygonize/polygonizer.h"
#include "refine/refiner.h"

namespace isomesh {
namespace {

struct Surface {
    const char* name;
    const char* expression;  // with a parameter a
    double a;
    double a_changed;
    Box box;
};

Box cube(double r) {
    return {glm::dvec3(-r), glm::dvec3(r)};
}

const Surface kSurfaces[] = {
    {"sphere", "x^2+y^2+z^2=a", 4.0, 4.2, cube(5)},
    {"cosine_sphere", "x^2+y^2+z^2+2cos(2x)=a", 5.0, 5.2, cube(5)},
    {"torus", "(sqrt(x^2+y^2)-2)^2+z^2=a", 0.64, 0.7, cube(5)},
    {"gyroid", "sin(x)cos(y)+sin(y)cos(z)+sin(z)cos(x)=a", 0.0, 0.1, cube(6)},
    {"heart", "(x^2+2.25y^2+z^2-1)^3-x^2z^3-0.1125y^2z^3=a", 0.0, 0.02, cube(1.5)},
    {"genus_two",
     "((x^2+y^2)^2-x^2+y^2)^2+z^2=a",
     0.01,
     0.012,
     {{-1.4, -0.9, -0.3}, {1.4, 0.9, 0.3}}},
};

class Fnv {
  public:
    template <typename T>
    void add(const T& value) {
        unsigned char bytes[sizeof(T)];
        std::memcpy(bytes, &value, sizeof(T));
        for (unsigned char b : bytes) hash_ = (hash_ ^ b) * 0x100000001b3ull;
    }
    template <typename T>
    void add_all(const std::vector<T>& values) {
        add(values.size());
        for (const T& v : values) add(v);
    }
    std::uint64_t value() const { return hash_; }

  private:
    std::uint64_t hash_ = 0xcbf29ce484222325ull;
};

void add_vertices(Fnv& h, const std::vector<DeltaVertex>& vertices) {
    h.add(vertices.size());
    for (const DeltaVertex& v : vertices) {
        h.add(v.id);
        h.add(v.position);
        h.add(v.normal);
    }
}

void add_delta(Fnv& h, const MeshDelta& d) {
    h.add_all(d.removed_triangles);
    h.add_all(d.removed_vertices);
    add_vertices(h, d.added_vertices);
    add_vertices(h, d.moved_vertices);
    h.add(d.added_triangles.size());
    for (const DeltaTriangle& t : d.added_triangles) {
        h.add(t.id);
        h.add(t.vertices);
    }
}

std::shared_ptr<const Field> field_of(const Surface& s, double a) {
    static std::map<std::string, std::shared_ptr<const Tape>> tapes;
    auto& tape = tapes[s.expression];
    if (!tape) tape = std::make_shared<const Tape>(compile_expression(s.expression).tape);
    return make_tape_field(tape, bind_parameters(*tape, {{"a", a}}).values);
}

std::size_t converge(Refiner& refiner, Fnv& deltas) {
    std::size_t steps = 0;
    for (;; ++steps) {
        const StepResult r = refiner.step(StepBudget(1000));
        add_delta(deltas, r.delta);
        if (r.converged) return steps;
    }
}

void digest(const Surface& s, const char* measure, int threads) {
    const auto field = field_of(s, s.a);
    PolygonizeSettings phase1;
    phase1.box = s.box;
    phase1.min_depth = kRefinePhase1MinDepth;
    phase1.threads = threads;
    const Mesh first = polygonize(*field, phase1).mesh;
    RefineSettings settings;
    // Budgets above the phase-1 mesh (the heart's and the genus-2 surface's have over 40,000).
    const std::size_t roots = first.triangles.size();
    settings.constraint = Constraint::triangle_budget(roots + 40000);
    settings.error_measure = make_error_measure(measure);
    settings.box = s.box;
    Refiner refiner(field, first, settings);
    Fnv deltas;
    add_delta(deltas, refiner.snapshot());
    std::size_t steps = converge(refiner, deltas);
    for (std::size_t budget : {10000, 30000}) {
        refiner.set_constraint(Constraint::triangle_budget(roots + budget));
        steps += converge(refiner, deltas);
    }
    refiner.set_field(field_of(s, s.a_changed));
    steps += converge(refiner, deltas);
    const RefinedMesh mesh = refiner.mesh();
    Fnv final_mesh;
    final_mesh.add_all(mesh.mesh.positions);
    final_mesh.add_all(mesh.mesh.triangles);
    final_mesh.add_all(mesh.vertex_ids);
    final_mesh.add_all(mesh.triangle_ids);
    const RefineCounters& c = refiner.counters();
    std::printf(
        "%-14s %-9s threads %d: deltas %016llx mesh %016llx  (%zu triangles, %zu splits, "
        "%zu merges, %zu steps)\n",
        s.name, measure, threads, static_cast<unsigned long long>(deltas.value()),
        static_cast<unsigned long long>(final_mesh.value()), mesh.mesh.triangles.size(), c.splits,
        c.merges, steps);
}

}  // namespace
}  // namespace isomesh

int main() {
    for (const isomesh::Surface& s : isomesh::kSurfaces)
        for (const char* measure : {"distance", "epsilon4"})
            for (int threads : {1, 2}) isomesh::digest(s, measure, threads);
    return 0;
}
