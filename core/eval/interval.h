// Interval arithmetic result type (Moore 1966; Snyder, "Interval analysis for computer graphics",
// SIGGRAPH 1992; Duff, "Interval arithmetic and recursive subdivision for implicit functions and
// constructive solid geometry", SIGGRAPH 1992).
#pragma once

#include <limits>

namespace isomesh {

/// A closed interval [lo, hi]; lo may be -inf and hi +inf. An empty interval (the function is
/// undefined everywhere in the box) has lo > hi; see Interval::empty().
struct Interval {
    double lo = 0.0;
    double hi = 0.0;

    static constexpr Interval empty() {
        return {std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
    }
    static constexpr Interval entire() {
        return {-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
    }
    bool is_empty() const { return !(lo <= hi); }
    bool contains(double v) const { return lo <= v && v <= hi; }
    /// True when every value is > 0, or every value is < 0: f has no root in the box.
    bool excludes_zero() const { return lo > 0.0 || hi < 0.0; }
};

/// What interval evaluation knows about f on a box.
struct IntervalValue {
    Interval value;
    /// f may jump somewhere in the box (a pole such as 1/x at x = 0, tan at pi/2, floor at an
    /// integer): a sign change inside the box need not be a root. The mesher must confirm roots
    /// numerically in such boxes, so `1/x = 0` gives no surface.
    bool maybe_discontinuous = false;
    /// f may be undefined (NaN) somewhere in the box (sqrt or ln of a negative number, acos
    /// outside [-1, 1], 0/0).
    bool maybe_undefined = false;
};

}  // namespace isomesh
