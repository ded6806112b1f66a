// Splits and merges on the forest of triangles (ROAM, Duchaineau et al. 1997: forced splits and
// diamond merges; newest vertex bisection, Mitchell 1989). A split bisects the base edge of a
// triangle and of its base neighbour (a diamond), after the forced splits that make the
// neighbour's base edge the same; a merge undoes one such bisection once its children are leaves.
#include <cassert>
#include <cmath>

#include "refine/refiner_impl.h"

namespace isomesh {

using namespace refiner_detail;

// ---------------------------------------------------------------------------------------------
// Splits

bool Refiner::Impl::plan_split(std::uint32_t t, SplitPlan& plan) {
    plan.chain.clear();
    plan.added_triangles = 0;
    for (std::uint32_t current = t;;) {
        if (!splittable(current)) return false;
        plan.chain.push_back(current);
        const std::uint32_t n = triangles_[current].nb[triangles_[current].base];
        if (n == kNone || is_diamond(current, n)) {
            if (n != kNone && !splittable(n)) return false;
            plan.partner = n;
            plan.added_triangles += n == kNone ? 1 : 2;
            return true;
        }
        plan.added_triangles += 2;
        if (plan.chain.size() > settings_.max_forced_chain) {
            ++counters_.refused_splits;
            return false;
        }
        current = n;
    }
}

namespace {

/// A triangle of geometric normal `n` stands clearly against the surface's normals at its
/// corners (their sum): the angle between them is over about 104 degrees (cosine below -0.25).
/// Marching Cubes can stand a triangle nearly across the surface where the lattice barely cuts a
/// ridge (cosine near 0, either sign); only such clear folds are inside out.
bool clear_fold(const glm::dvec3& n, const glm::dvec3& corner_normals) {
    const double d = glm::dot(n, corner_normals);
    // The right side is never positive: no square roots where the triangle faces along them.
    if (!(d < 0.0)) return false;
    return d < -0.25 * glm::length(n) * glm::length(corner_normals);
}

/// |v| <= bound, without the square root where |v|^2 is clearly larger (the same answer: then
/// |v| > bound, also where bound^2 underflows).
bool length_at_most(const glm::dvec3& v, double bound) {
    const double squared = glm::dot(v, v);
    if (squared > 4.0 * bound * bound) return false;
    return std::sqrt(squared) <= bound;
}

}  // namespace

Refiner::Impl::SplitCorners Refiner::Impl::split_corners(std::uint32_t t) const {
    const Triangle& T = triangles_[t];
    return {position(t, T.base), position(t, T.base + 1), position(t, T.base + 2),
            normal(t, T.base),   normal(t, T.base + 1),   normal(t, T.base + 2)};
}

bool Refiner::Impl::folds(const SplitCorners& k, const glm::dvec3& m, const glm::dvec3& m_normal) {
    const glm::dvec3 parent = glm::cross(k.b - k.a, k.c - k.a);
    const glm::dvec3 parent_normals = k.na + k.nb + k.nc;
    const bool parent_faces_out = glm::dot(parent, parent_normals) > 0.0;
    const bool parent_folded = clear_fold(parent, parent_normals);
    // The half (p, q, c) of the triangle, with the sum of its corners' normals.
    const auto half_folds = [&](const glm::dvec3& p, const glm::dvec3& q,
                                const glm::dvec3& half_normals) {
        const glm::dvec3 child = glm::cross(q - p, k.c - p);
        const double longest = std::max(
            {glm::dot(q - p, q - p), glm::dot(k.c - q, k.c - q), glm::dot(p - k.c, p - k.c)});
        // Flipped against the parent, or of zero area (|cross| <= 1e-14 longest^2).
        if (!(glm::dot(child, parent) > 0.0) || length_at_most(child, 1e-14 * longest)) return true;
        // On a coarse (simplified) mesh a child can keep its parent's side yet face the
        // surface's inside: a parent facing the way its corners' normals do (towards f > 0) gets
        // no child that does not, and no split makes a clear fold where there was none.
        if (parent_faces_out && !(glm::dot(child, half_normals) > 0.0)) return true;
        return !parent_folded && clear_fold(child, half_normals);
    };
    return half_folds(k.a, m, k.na + m_normal + k.nc) || half_folds(m, k.b, m_normal + k.nb + k.nc);
}

void Refiner::Impl::block(std::uint32_t t) {
    if (!split_queue_->contains(t)) return;
    split_queue_->remove(t);
    blocked_queue_->insert(t, triangles_[t].error);
}

bool Refiner::Impl::prepare(const SplitPlan& plan) {
    ensure_candidates(plan.chain, /*look_ahead=*/true);
    bool ok = true, retried = false;
    for (std::size_t i = 0; i < plan.chain.size(); ++i) {
        Triangle& T = triangles_[plan.chain[i]];
        // The split vertex must not fold the children over (the surface turns sharply between
        // the base edge's ends) nor make one of zero area.
        if (!T.candidate_refused && split_folds(plan, i)) T.candidate_refused = true;
        if (T.candidate_refused && !T.candidate_retried) {
            T.candidate_refused = !retry_candidate(plan, i);
            retried = retried || !T.candidate_refused;
        }
        if (!T.candidate_refused) continue;
        ok = false;
        refuse(plan.chain[i]);
    }
    if (!ok || !retried) return ok;
    // A retried vertex of chain[i + 1] is the apex of the other half of chain[i]'s diamond,
    // which was checked with the vertex it replaced.
    for (std::size_t i = 0; i + 1 < plan.chain.size(); ++i) {
        if (!split_folds(plan, i)) continue;
        triangles_[plan.chain[i]].candidate_refused = true;
        ok = false;
        refuse(plan.chain[i]);
    }
    return ok;
}

void Refiner::Impl::refuse(std::uint32_t t) {
    ++counters_.refused_vertices;
    block(t);  // kept, unsplit, until the function changes
}

bool Refiner::Impl::split_folds(const SplitPlan& plan, std::size_t i) const {
    const std::uint32_t t = plan.chain[i];
    const Triangle& T = triangles_[t];
    const SplitCorners own = split_corners(t);
    if (folds(own, T.candidate, T.candidate_normal)) return true;
    if (i + 1 < plan.chain.size()) {
        // The other half of the diamond does not exist yet: it is the child of chain[i + 1]'s
        // split across t's base edge, with that split's vertex as its apex.
        const Triangle& next = triangles_[plan.chain[i + 1]];
        const SplitCorners across{own.b,  own.a,  next.candidate,
                                  own.nb, own.na, next.candidate_normal};
        return folds(across, T.candidate, T.candidate_normal);
    }
    return plan.partner != kNone &&
           folds(split_corners(plan.partner), T.candidate, T.candidate_normal);
}

bool Refiner::Impl::retry_candidate(const SplitPlan& plan, std::size_t i) {
    const std::uint32_t t = plan.chain[i];
    // The triangle across the base edge: the diamond partner, or the next of the chain (whose
    // child across t's base will lie in its plane, up to its own split vertex).
    const std::uint32_t across = i + 1 < plan.chain.size() ? plan.chain[i + 1] : plan.partner;
    triangles_[t].candidate_retried = true;
    const bool diamond = i + 1 == plan.chain.size() && plan.partner != kNone;
    if (diamond) triangles_[plan.partner].candidate_retried = true;  // the same point
    // Where the vertex normals at the base's ends diverge (a coarse triangle across a strongly
    // curved region), their mean leads the search line to a point beside the diamond, whose
    // children fold. Along the sum of the two faces' unit normals the point stays on the line
    // through the base midpoint perpendicular to the base in both planes' projections, where
    // neither triangle's children flip (symmetric: both triangles of a diamond find it).
    const auto face_normal = [this](std::uint32_t u) {
        const SplitCorners k = split_corners(u);
        return unit_or_zero(glm::cross(k.b - k.a, k.c - k.a));
    };
    ProjectionRequest request = candidate_request(t);
    request.direction = face_normal(t) + (across == kNone ? glm::dvec3(0.0) : face_normal(across));
    const Projection p = project_to_surface(*evaluator_, request, settings_.projection);
    if (!p.on_surface() || !settings_.box.contains(p.position)) return false;
    Triangle& T = triangles_[t];
    const Triangle before = T;
    T.candidate = p.position;
    T.candidate_normal = p.normal;
    T.candidate_gradient_norm = p.gradient_norm;
    T.candidate_on_surface = true;
    T.midpoint_value_known = false;
    if (split_folds(plan, i)) {
        T = before;
        return false;
    }
    if (diamond) {
        Triangle& P = triangles_[plan.partner];
        P.candidate = T.candidate;
        P.candidate_normal = T.candidate_normal;
        P.candidate_gradient_norm = T.candidate_gradient_norm;
        P.candidate_on_surface = true;
        P.candidate_refused = false;
        P.midpoint_value_known = false;
    }
    return true;
}

void Refiner::Impl::execute(const SplitPlan& plan) {
    // Bisect from the far end of the chain back to the triangle that asked: after chain[i + 1] is
    // bisected, its child across chain[i]'s base edge has that edge as its own base edge.
    bisect(plan.chain.back(), plan.partner);
    for (std::size_t i = plan.chain.size() - 1; i-- > 0;) {
        const std::uint32_t t = plan.chain[i];
        const std::uint32_t n = triangles_[t].nb[triangles_[t].base];
        assert(is_diamond(t, n));
        bisect(t, n);
    }
}

std::uint32_t Refiner::Impl::make_child(std::uint32_t record, std::uint8_t base) {
    const std::uint32_t slot = triangles_.allocate();
    Triangle& C = triangles_[slot];
    C.id = next_triangle_id_++;
    C.base = base;
    C.parent = record;
    return slot;
}

void Refiner::Impl::bisect(std::uint32_t t, std::uint32_t n) {
    const std::array<std::uint32_t, 2> pair{t, n};
    ensure_errors({pair.data(), n == kNone ? 1u : 2u});
    ensure_candidates({&t, 1});
    const std::uint32_t record = records_.allocate();
    const std::uint32_t m = vertices_.allocate();
    {
        const Triangle& T = triangles_[t];
        Vertex& M = vertices_[m];
        M.id = next_vertex_id_++;
        M.position = T.candidate;
        M.normal = T.candidate_normal;
        M.gradient_norm = T.candidate_gradient_norm;
        M.on_surface = T.candidate_on_surface;
        assert(M.on_surface && !T.candidate_refused);  // prepare() refused the plan otherwise
        M.scale = base_length(t);
        M.version = version_;
        M.fixed_axes = n == kNone ? face_axes(vertices_[T.v[T.base]].position,
                                              vertices_[T.v[(T.base + 1) % 3]].position, bounds_)
                                  : 0;
        M.alive = true;
        delta_.add_vertex(M.id, m);
    }
    remove_leaf(t);
    if (n != kNone) remove_leaf(n);

    // T = (a, b, c) with base a-b becomes (a, m, c) and (m, b, c); N = (b, a, d) becomes
    // (b, m, d) and (m, a, d). Neighbour slots across the half-base edges are filled below.
    const std::array<std::uint32_t, 2> parents{t, n};
    std::array<std::uint32_t, 4> children{kNone, kNone, kNone, kNone};
    for (int side = 0; side < 2; ++side) {
        const std::uint32_t p = parents[side];
        if (p == kNone) continue;
        // Copies: make_child may move the pool.
        const int b = triangles_[p].base;
        const std::array<std::uint32_t, 3> v = triangles_[p].v, nb = triangles_[p].nb;
        const std::uint32_t a = v[b], bb = v[(b + 1) % 3], c = v[(b + 2) % 3];
        // The corners and neighbours are written here rather than passed to make_child: arrays
        // of three 32-bit words passed by value went through the stack, written as words and read
        // back in wider loads, which wait for the writes (a store-forwarding stall: half of
        // bisect's time in perf).
        const std::uint32_t first = make_child(record, 2);
        triangles_[first].v = {a, m, c};
        triangles_[first].nb = {kNone, kNone, nb[(b + 2) % 3]};
        const std::uint32_t second = make_child(record, 1);
        triangles_[second].v = {m, bb, c};
        triangles_[second].nb = {kNone, nb[(b + 1) % 3], first};
        triangles_[first].nb[1] = second;
        replace_neighbour(nb[(b + 2) % 3], p, first);
        replace_neighbour(nb[(b + 1) % 3], p, second);
        children[2 * side] = first;
        children[2 * side + 1] = second;
        Triangle& Pm = triangles_[p];
        Pm.state = TriangleState::Split;
        Pm.split = record;
        child_was_split(Pm.parent);
    }
    if (n != kNone) {  // (a, m) borders (m, a); (m, b) borders (b, m)
        triangles_[children[0]].nb[0] = children[3];
        triangles_[children[3]].nb[0] = children[0];
        triangles_[children[1]].nb[0] = children[2];
        triangles_[children[2]].nb[0] = children[1];
    }
    SplitRecord& R = records_[record];
    R.vertex = m;
    R.parents = parents;
    R.children = children;
    R.split_children = 0;
    R.alive = true;
    const std::size_t child_count = n == kNone ? 2 : 4;
    ensure_errors({children.data(), child_count});
    for (std::size_t i = 0; i < child_count; ++i) add_leaf(children[i]);
    merge_queue_->insert(record, merge_priority(record));
    ++counters_.splits;
}

// ---------------------------------------------------------------------------------------------
// Merges

void Refiner::Impl::merge(std::uint32_t record) {
    merge_queue_->remove(record);
    const SplitRecord R = records_[record];
    assert(R.alive && R.split_children == 0);
    for (std::uint32_t c : R.children)
        if (c != kNone) remove_leaf(c);
    const Vertex& M = vertices_[R.vertex];
    for (int side = 0; side < 2; ++side) {
        const std::uint32_t p = R.parents[side];
        if (p == kNone) continue;
        const std::uint32_t first = R.children[2 * side], second = R.children[2 * side + 1];
        Triangle& P = triangles_[p];
        const int b = P.base;
        P.nb[(b + 2) % 3] = triangles_[first].nb[2];
        P.nb[(b + 1) % 3] = triangles_[second].nb[1];
        replace_neighbour(P.nb[(b + 2) % 3], first, p);
        replace_neighbour(P.nb[(b + 1) % 3], second, p);
        // The removed vertex is the parent's projected base midpoint.
        P.candidate = M.position;
        P.candidate_normal = M.normal;
        P.candidate_gradient_norm = M.gradient_norm;
        P.candidate_on_surface = M.on_surface;
        P.candidate_version = M.version;
        P.midpoint_value_known = false;
    }
    delta_.remove_vertex(M.id);
    vertices_[R.vertex].alive = false;
    vertices_.release(R.vertex);
    for (std::uint32_t c : R.children) {
        if (c == kNone) continue;
        triangles_[c].state = TriangleState::Free;
        triangles_.release(c);
    }
    records_[record].alive = false;
    records_.release(record);
    for (std::uint32_t p : R.parents) {
        if (p == kNone) continue;
        triangles_[p].state = TriangleState::Leaf;  // its midpoint is now its candidate
        ensure_errors({&p, 1});
        add_leaf(p);
        child_became_leaf(triangles_[p].parent);
    }
    ++counters_.merges;
}

MeshStats Refiner::Impl::stats_after_merge(const MeshStats& stats, std::uint32_t record) {
    const SplitRecord& R = records_[record];
    MeshStats after = stats;
    for (std::uint32_t c : R.children) {
        if (c == kNone) continue;
        --after.triangles;
        after.total_error -= triangles_[c].error;
    }
    for (std::uint32_t p : R.parents) {
        if (p == kNone) continue;
        ++after.triangles;
        const double e = parent_error(p);
        after.total_error += e;
        after.max_error = std::max(after.max_error, e);  // an upper bound: children leave
    }
    return after;
}

}  // namespace isomesh
