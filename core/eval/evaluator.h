// The evaluator interface: all the mesher and the refiner ever see of a function.
//
// A Field is an immutable, thread-safe description of a scalar function f: R^3 -> R (a compiled
// tape with its parameter values, or a sampled grid). Each worker thread asks it for its own
// Evaluator, which holds scratch memory and is used by that thread alone (libfive's and Fidget's
// model: one evaluator per worker). The surface is f = 0, with f > 0 outside.
//
// Every evaluator must satisfy the conformance suite in tests/eval/: the four kinds of evaluation
// agree with each other, and interval results are sound (contain every value f takes on the box).
#pragma once

#include <cstddef>
#include <memory>
#include <span>

#include <glm/vec3.hpp>

#include "eval/interval.h"

namespace isomesh {

/// An axis-aligned box [lo.x, hi.x] x [lo.y, hi.y] x [lo.z, hi.z]; lo <= hi componentwise.
struct Box {
    glm::dvec3 lo{0.0};
    glm::dvec3 hi{0.0};

    glm::dvec3 size() const { return hi - lo; }
    glm::dvec3 center() const { return 0.5 * (lo + hi); }
    bool contains(const glm::dvec3& p) const {
        return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z &&
               p.z <= hi.z;
    }
};

/// f and its gradient at one point, from one pass (forward-mode automatic differentiation).
struct ValueGradient {
    double value = 0.0;
    glm::dvec3 gradient{0.0};
};

/// Enclosures of f and of its gradient over a box (interval forward-mode differentiation).
/// gradient[i] encloses df/dx_i wherever f is differentiable in the box; a component that is
/// entire means nothing is known. The mesher uses it to prove that f is monotone along a cell
/// edge (so the edge is crossed at most once).
struct IntervalGradient {
    IntervalValue value;
    Interval gradient[3];
};

/// Structure-of-arrays points for batch evaluation: x[i], y[i], z[i] is point i.
struct PointBatch {
    std::span<const double> x;
    std::span<const double> y;
    std::span<const double> z;
    std::size_t size() const { return x.size(); }
};

class Evaluator {
public:
    virtual ~Evaluator() = default;

    /// f(p). NaN where f is undefined (ln of a negative number, 0/0, outside a grid...).
    virtual double value(const glm::dvec3& p) = 0;

    /// out[i] = f(points[i]) for every i. Precondition: x, y, z and out have the same size.
    /// Results are bit-identical to value() at the same points.
    virtual void values(const PointBatch& points, std::span<double> out) = 0;

    /// A sound enclosure of f over the box: every value f takes at a point of the box where it is
    /// defined lies in the result's interval, and the flags say whether f may be discontinuous or
    /// undefined somewhere in the box (see IntervalValue).
    virtual IntervalValue interval(const Box& box) = 0;

    /// f(p) and grad f(p). The value is identical to value(p).
    virtual ValueGradient value_gradient(const glm::dvec3& p) = 0;

    /// Sound enclosures of f and grad f over the box (see IntervalGradient).
    virtual IntervalGradient interval_gradient(const Box& box) = 0;

    // Batched forms: one call for many points or boxes (an octree cell's 8 children, the corners
    // of many cells), so that an evaluator can run its program once for all of them. Each result
    // is bit-identical to the single call's at the same point or box. Preconditions: equal sizes.
    // The defaults loop over the single calls.

    /// out[i] = value_gradient(points[i]).
    virtual void value_gradients(const PointBatch& points, std::span<ValueGradient> out);
    /// out[i] = interval(boxes[i]).
    virtual void intervals(std::span<const Box> boxes, std::span<IntervalValue> out);
    /// out[i] = interval_gradient(boxes[i]).
    virtual void interval_gradients(std::span<const Box> boxes, std::span<IntervalGradient> out);

    /// Tape simplification (libfive, Fidget): specialises the evaluator to `box`, for example by
    /// dropping min/max branches that interval evaluation proves irrelevant there. Until the
    /// matching pop(), evaluations must be at points inside the box (or boxes inside it) and give
    /// the same results as without the push. Pushes nest. The default does nothing.
    virtual void push(const Box& box) { (void)box; }
    virtual void pop() {}
};

class Field {
public:
    virtual ~Field() = default;
    /// A new evaluator for the calling thread. Thread-safe.
    virtual std::unique_ptr<Evaluator> make_evaluator() const = 0;
    /// The box outside which the field is undefined (a sampled grid's extent), or an infinite box.
    virtual Box domain() const;
};

}  // namespace isomesh
