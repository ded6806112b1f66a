// Constraint functions (thesis Definition 18): when the refiner should stop splitting.
//
// A constraint answers two questions about a mesh, given by its statistics:
// - wants_refinement: the thesis's delta(M), true while the mesh is not detailed enough. The
//   refiner splits while it is true, and merges while it stays false after the merge (a raised
//   error bound coarsens the mesh).
// - over_limit: the mesh breaks a hard cap (a triangle budget) and must be coarsened even at the
//   price of accuracy (a lowered budget). Only triangle budgets set caps.
// Constraints compose with all_of (and), any_of (or) and negate (not). The thesis's
// delta(M) = (max error > alpha) and (|M| < N) is all_of(max_error(alpha), triangle_budget(N)).
//
// Composition of caps: all_of is over its limit when any part is (each conjunct is a cap);
// any_of only when every part is (a budget inside an or is a minimum, not a cap); negate never.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace isomesh {

/// What constraints see of a mesh.
struct MeshStats {
    std::size_t triangles = 0;
    /// Sum and maximum of the error measure over the mesh's triangles.
    double total_error = 0.0;
    double max_error = 0.0;
};

class Constraint {
  public:
    /// Never wants refinement (the default: a refiner without constraint does nothing).
    Constraint();

    /// Refine while the mesh has fewer than `triangles` triangles; over the limit above it.
    static Constraint triangle_budget(std::size_t triangles);
    /// Refine while some triangle's error exceeds `error` (thesis: local error bound).
    static Constraint max_error(double error);
    /// What a user asks for: refine up to `triangles`, and, when `max_error` > 0, stop once no
    /// triangle's error exceeds it: max_error(e) && triangle_budget(n), or the budget alone.
    static Constraint budget_and_error_bound(std::size_t triangles, double max_error);
    /// Refine while the errors sum to more than `error` (thesis: global error bound).
    static Constraint total_error(double error);
    /// Any predicate on the statistics; it should be monotone (false stays false as the mesh is
    /// refined), as Definition 18 requires. Never over a limit.
    static Constraint custom(std::function<bool(const MeshStats&)> wants_refinement,
                             std::string description = "custom");

    static Constraint all_of(std::vector<Constraint> parts);
    static Constraint any_of(std::vector<Constraint> parts);
    static Constraint negate(Constraint part);

    bool wants_refinement(const MeshStats& stats) const;
    bool over_limit(const MeshStats& stats) const;
    /// The largest triangle count that is not over_limit (whatever the errors), or nullopt when
    /// there is no such cap.
    std::optional<std::size_t> triangle_limit() const;
    /// Whether wants_refinement or over_limit may read MeshStats::max_error (a custom predicate
    /// may): a refiner leaves it out of the statistics it asks about otherwise.
    bool reads_max_error() const;
    /// A readable form, e.g. "(triangles < 1000 and max_error > 0.01)".
    std::string describe() const;

    struct Node;

  private:
    explicit Constraint(std::shared_ptr<const Node> node) : node_(std::move(node)) {}
    std::shared_ptr<const Node> node_;
};

Constraint operator&&(Constraint a, Constraint b);
Constraint operator||(Constraint a, Constraint b);
Constraint operator!(Constraint a);

}  // namespace isomesh
