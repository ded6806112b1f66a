// Recovering the splits of a net delta, newest first (see split_inference.h).
#include "protocol/split_inference.h"

#include <algorithm>
#include <unordered_map>

#include <glm/geometric.hpp>

namespace isomesh::protocol {
namespace {

using Corners = std::array<std::uint32_t, 3>;

/// The working mesh: triangles as corner triples (oriented), reachable from each corner.
class Stars {
  public:
    void add(const Corners& c) {
        for (std::uint32_t v : c) stars_[v].push_back(c);
    }
    void remove(const Corners& c) {
        const Corners key = canonical_rotation(c);
        for (std::uint32_t v : c) {
            auto& star = stars_[v];
            auto it = std::find_if(star.begin(), star.end(),
                                   [&](const Corners& t) { return canonical_rotation(t) == key; });
            if (it != star.end()) star.erase(it);
        }
    }
    /// The triangles around `v`, each rotated to start at v.
    std::vector<Corners> around(std::uint32_t v) const {
        std::vector<Corners> out;
        auto it = stars_.find(v);
        if (it == stars_.end()) return out;
        for (const Corners& c : it->second) {
            const int k = c[0] == v ? 0 : c[1] == v ? 1 : 2;
            out.push_back({c[k], c[(k + 1) % 3], c[(k + 2) % 3]});
        }
        return out;
    }

  private:
    std::unordered_map<std::uint32_t, std::vector<Corners>> stars_;
};

struct Reading {
    std::uint32_t p, q;  // the split edge
    std::array<Corners, 2> parents;
    int parent_count;
};

/// A parent (p, q, r) made by a split has r as its newest vertex.
int newest_apex_score(const Reading& r) {
    int score = 0;
    for (int i = 0; i < r.parent_count; ++i) {
        const Corners& c = r.parents[i];
        if (c[2] > c[0] && c[2] > c[1]) ++score;
    }
    return score;
}

/// The star (v, x, y) of two children: (v, r, p) and (v, q, r) from the parent (p, q, r).
std::optional<Reading> read_two(const std::vector<Corners>& star) {
    for (int first = 0; first < 2; ++first) {
        const Corners& a = star[first];
        const Corners& b = star[1 - first];
        if (a[1] == b[2]) return Reading{a[2], b[1], {Corners{a[2], b[1], a[1]}, Corners{}}, 1};
    }
    return std::nullopt;
}

std::optional<Reading> read_four(const std::vector<Corners>& star,
                                 const std::function<glm::vec3(std::uint32_t)>& position) {
    std::unordered_map<std::uint32_t, std::uint32_t> next;
    for (const Corners& c : star) next[c[1]] = c[2];
    std::array<std::uint32_t, 4> ring{};
    ring[0] = star[0][1];
    for (int i = 1; i < 4; ++i) {
        auto it = next.find(ring[i - 1]);
        if (it == next.end()) return std::nullopt;
        ring[i] = it->second;
    }
    if (next.size() != 4 || next[ring[3]] != ring[0] || ring[2] == ring[0] || ring[3] == ring[1])
        return std::nullopt;
    // Apexes ring[i] and ring[i + 2]; the split edge joins the other two.
    auto reading = [&](int i) {
        const std::uint32_t r0 = ring[i], r1 = ring[(i + 1) % 4], r2 = ring[(i + 2) % 4],
                            r3 = ring[(i + 3) % 4];
        return Reading{r1, r3, {Corners{r1, r3, r0}, Corners{r3, r1, r2}}, 2};
    };
    const Reading a = reading(0);
    const Reading b = reading(1);
    const int score_a = newest_apex_score(a);
    const int score_b = newest_apex_score(b);
    if (score_a != score_b) return score_a > score_b ? a : b;
    const auto length = [&](const Reading& r) {
        const glm::vec3 d = position(r.p) - position(r.q);
        return glm::dot(d, d);
    };
    return length(a) >= length(b) ? a : b;
}

}  // namespace

SplitInference infer_splits(std::span<const std::uint32_t> new_vertices,
                            std::span<const Triangle> added,
                            const std::function<glm::vec3(std::uint32_t)>& position) {
    Stars stars;
    for (const Triangle& t : added) stars.add(t.vertices);
    SplitInference out;
    for (auto it = new_vertices.rbegin(); it != new_vertices.rend(); ++it) {
        const std::uint32_t v = *it;
        const std::vector<Corners> star = stars.around(v);
        std::optional<Reading> reading;
        if (star.size() == 2) reading = read_two(star);
        if (star.size() == 4) reading = read_four(star, position);
        if (!reading) {
            out.loose.push_back(v);
            continue;
        }
        for (const Corners& c : star) stars.remove(c);
        for (int i = 0; i < reading->parent_count; ++i) stars.add(reading->parents[i]);
        out.splits.push_back({v, reading->p, reading->q});
    }
    std::reverse(out.splits.begin(), out.splits.end());
    std::reverse(out.loose.begin(), out.loose.end());
    return out;
}

}  // namespace isomesh::protocol
