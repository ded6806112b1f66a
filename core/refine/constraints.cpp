// Composable constraint functions (the thesis, Definition 18 and section 3.2.3 "Constraints").
#include "refine/constraints.h"

#include <algorithm>
#include <sstream>

namespace isomesh {

struct Constraint::Node {
    enum class Kind { Never, TriangleBudget, MaxError, TotalError, Custom, AllOf, AnyOf, Not };
    Kind kind = Kind::Never;
    double bound = 0.0;
    std::function<bool(const MeshStats&)> predicate;
    std::string description;
    std::vector<Constraint> parts;
};

namespace {

using Kind = Constraint::Node::Kind;

std::shared_ptr<const Constraint::Node> make_node(Kind kind, double bound = 0.0) {
    auto node = std::make_shared<Constraint::Node>();
    node->kind = kind;
    node->bound = bound;
    return node;
}

}  // namespace

Constraint::Constraint() : node_(make_node(Kind::Never)) {}

Constraint Constraint::triangle_budget(std::size_t triangles) {
    return Constraint(make_node(Kind::TriangleBudget, static_cast<double>(triangles)));
}

Constraint Constraint::max_error(double error) {
    return Constraint(make_node(Kind::MaxError, error));
}

Constraint Constraint::budget_and_error_bound(std::size_t triangles, double max_error) {
    Constraint budget = triangle_budget(triangles);
    if (max_error <= 0) return budget;
    return Constraint::max_error(max_error) && std::move(budget);
}

Constraint Constraint::total_error(double error) {
    return Constraint(make_node(Kind::TotalError, error));
}

Constraint Constraint::custom(std::function<bool(const MeshStats&)> wants_refinement,
                              std::string description) {
    auto node = std::make_shared<Node>();
    node->kind = Kind::Custom;
    node->predicate = std::move(wants_refinement);
    node->description = std::move(description);
    return Constraint(std::move(node));
}

Constraint Constraint::all_of(std::vector<Constraint> parts) {
    auto node = std::make_shared<Node>();
    node->kind = Kind::AllOf;
    node->parts = std::move(parts);
    return Constraint(std::move(node));
}

Constraint Constraint::any_of(std::vector<Constraint> parts) {
    auto node = std::make_shared<Node>();
    node->kind = Kind::AnyOf;
    node->parts = std::move(parts);
    return Constraint(std::move(node));
}

Constraint Constraint::negate(Constraint part) {
    auto node = std::make_shared<Node>();
    node->kind = Kind::Not;
    node->parts.push_back(std::move(part));
    return Constraint(std::move(node));
}

bool Constraint::wants_refinement(const MeshStats& stats) const {
    const Node& n = *node_;
    switch (n.kind) {
        case Kind::Never:
            return false;
        case Kind::TriangleBudget:
            return static_cast<double>(stats.triangles) < n.bound;
        case Kind::MaxError:
            return stats.max_error > n.bound;
        case Kind::TotalError:
            return stats.total_error > n.bound;
        case Kind::Custom:
            return n.predicate && n.predicate(stats);
        case Kind::AllOf:
            return std::all_of(n.parts.begin(), n.parts.end(),
                               [&](const Constraint& c) { return c.wants_refinement(stats); });
        case Kind::AnyOf:
            return std::any_of(n.parts.begin(), n.parts.end(),
                               [&](const Constraint& c) { return c.wants_refinement(stats); });
        case Kind::Not:
            return !n.parts.front().wants_refinement(stats);
    }
    return false;
}

bool Constraint::over_limit(const MeshStats& stats) const {
    const Node& n = *node_;
    switch (n.kind) {
        case Kind::TriangleBudget:
            return static_cast<double>(stats.triangles) > n.bound;
        case Kind::AllOf:
            return std::any_of(n.parts.begin(), n.parts.end(),
                               [&](const Constraint& c) { return c.over_limit(stats); });
        case Kind::AnyOf:
            return !n.parts.empty() &&
                   std::all_of(n.parts.begin(), n.parts.end(),
                               [&](const Constraint& c) { return c.over_limit(stats); });
        default:
            return false;
    }
}

bool Constraint::reads_max_error() const {
    const Node& n = *node_;
    switch (n.kind) {
        case Kind::MaxError:
        case Kind::Custom:
            return true;
        case Kind::AllOf:
        case Kind::AnyOf:
        case Kind::Not:
            return std::any_of(n.parts.begin(), n.parts.end(),
                               [](const Constraint& c) { return c.reads_max_error(); });
        default:
            return false;
    }
}

std::optional<std::size_t> Constraint::triangle_limit() const {
    const Node& n = *node_;
    std::optional<std::size_t> limit;
    switch (n.kind) {
        case Kind::TriangleBudget:
            return static_cast<std::size_t>(n.bound);
        case Kind::AllOf:  // any part's cap applies
            for (const Constraint& c : n.parts) {
                const auto part = c.triangle_limit();
                if (part) limit = limit ? std::min(*limit, *part) : *part;
            }
            return limit;
        case Kind::AnyOf:  // over the limit only when every part is
            for (const Constraint& c : n.parts) {
                const auto part = c.triangle_limit();
                if (!part) return std::nullopt;
                limit = limit ? std::max(*limit, *part) : *part;
            }
            return limit;
        default:
            return std::nullopt;
    }
}

std::string Constraint::describe() const {
    const Node& n = *node_;
    std::ostringstream out;
    auto join = [&](const char* separator) {
        out << '(';
        for (std::size_t i = 0; i < n.parts.size(); ++i)
            out << (i ? separator : "") << n.parts[i].describe();
        out << ')';
    };
    switch (n.kind) {
        case Kind::Never:
            out << "never";
            break;
        case Kind::TriangleBudget:
            out << "triangles < " << n.bound;
            break;
        case Kind::MaxError:
            out << "max_error > " << n.bound;
            break;
        case Kind::TotalError:
            out << "total_error > " << n.bound;
            break;
        case Kind::Custom:
            out << n.description;
            break;
        case Kind::AllOf:
            join(" and ");
            break;
        case Kind::AnyOf:
            join(" or ");
            break;
        case Kind::Not:
            out << "not " << n.parts.front().describe();
            break;
    }
    return out.str();
}

Constraint operator&&(Constraint a, Constraint b) {
    return Constraint::all_of({std::move(a), std::move(b)});
}

Constraint operator||(Constraint a, Constraint b) {
    return Constraint::any_of({std::move(a), std::move(b)});
}

Constraint operator!(Constraint a) {
    return Constraint::negate(std::move(a));
}

}  // namespace isomesh
