#include "polygonize/crossing_vertices.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace isomesh {

CrossingKey locate_crossing(CornerCache& values, const Lattice& lattice, const glm::u32vec3& lower,
                            int axis, int depth, int finest_depth) {
    assert(depth <= finest_depth && finest_depth <= lattice.max_depth());
    glm::u32vec3 lo = lower, hi = lower;
    std::uint32_t span = lattice.span(depth);
    const std::uint32_t finest = lattice.span(finest_depth);
    hi[axis] += span;
    const bool lo_inside = is_inside(values.value(lo));
    assert(lo_inside != is_inside(values.value(hi)));
    while (span > finest) {
        span /= 2;
        glm::u32vec3 mid = lo;
        mid[axis] += span;
        (is_inside(values.value(mid)) == lo_inside ? lo : hi) = mid;
    }
    return Lattice::edge_key(lo, axis) | std::uint64_t(finest_depth) << 53;
}

namespace {
constexpr std::uint64_t kPointMask = (std::uint64_t{1} << 51) - 1;
}

EdgeSegment crossing_segment(const ValueMap& values, const Lattice& lattice, CrossingKey key) {
    const int axis = static_cast<int>((key >> 51) & 3u);
    const int depth = static_cast<int>((key >> 53) & 31u);
    const glm::u32vec3 lo = Lattice::unkey(key & kPointMask);
    glm::u32vec3 hi = lo;
    hi[axis] += lattice.span(depth);
    return {lattice.point(lo), lattice.point(hi), values.at(Lattice::key(lo)),
            values.at(Lattice::key(hi)), axis};
}

glm::dvec3 approximate_crossing(const ValueMap& values, const Lattice& lattice, CrossingKey key) {
    const EdgeSegment s = crossing_segment(values, lattice, key);
    double t = 0.5;
    if (std::isfinite(s.fa) && std::isfinite(s.fb) && s.fa != s.fb) {
        t = std::clamp(s.fa / (s.fa - s.fb), 0.0, 1.0);
    }
    return s.at(t);
}

}  // namespace isomesh
