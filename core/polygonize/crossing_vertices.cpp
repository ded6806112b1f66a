#include "polygonize/crossing_vertices.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <vector>

namespace isomesh {

namespace {

/// One edge's bisection: [lo, hi] holds the sign change, `span` apart along `axis`.
struct Bracket {
    glm::u32vec3 lo{0u};
    glm::u32vec3 hi{0u};
    std::uint32_t span = 0;
    int axis = 0;
    bool lo_inside = false;

    glm::u32vec3 mid() const {
        glm::u32vec3 m = lo;
        m[axis] += span / 2;
        return m;
    }
};

}  // namespace

CrossingKey locate_crossing(CornerCache& values, const Lattice& lattice, const CellEdge& edge,
                            int finest_depth) {
    CrossingKey key = 0;
    locate_crossings(values, lattice, {&edge, 1}, finest_depth, {&key, 1});
    return key;
}

void locate_crossings(CornerCache& values, const Lattice& lattice, std::span<const CellEdge> edges,
                      int finest_depth, std::span<CrossingKey> out) {
    assert(edges.size() == out.size());
    const std::uint32_t finest = lattice.span(finest_depth);
    std::vector<Bracket> brackets(edges.size());
    for (std::size_t i = 0; i < edges.size(); ++i) {
        const CellEdge& e = edges[i];
        assert(e.depth <= finest_depth && finest_depth <= lattice.max_depth());
        Bracket& b = brackets[i];
        b.lo = b.hi = e.lower;
        b.span = lattice.span(e.depth);
        b.hi[e.axis] += b.span;
        b.axis = e.axis;
        b.lo_inside = is_inside(values.value(b.lo));
        assert(b.lo_inside != is_inside(values.value(b.hi)));
    }
    std::vector<glm::u32vec3> mids;
    for (;;) {
        mids.clear();
        for (const Bracket& b : brackets) {
            if (b.span > finest) mids.push_back(b.mid());
        }
        if (mids.empty()) break;
        values.prefetch(mids);
        for (Bracket& b : brackets) {
            if (b.span <= finest) continue;
            const glm::u32vec3 mid = b.mid();
            (is_inside(values.value(mid)) == b.lo_inside ? b.lo : b.hi) = mid;
            b.span /= 2;
        }
    }
    for (std::size_t i = 0; i < edges.size(); ++i) {
        out[i] = Lattice::edge_key(brackets[i].lo, brackets[i].axis) | std::uint64_t(finest_depth)
                                                                           << 53;
    }
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
