// Version-2 delta frames (see delta_v2.h; layout in PROTOCOL.md 4.5).
//
// Body, one range-coded stream (range_coder.h), in the order a decoder applies it:
//   rounds, then per round: split count, and per split: triangle id (ascending in the round: the
//     first minus 0, each next minus the previous minus 1), edge code, position residual (3
//     signed), normal residual (2 signed);
//   explicit removals: count, ids ascending (same difference coding);
//   loose vertices: count, each: position (3 x position_bits direct bits), normal (2 x
//     normal_bits direct bits, each coordinate + its maximum);
//   explicit triangles: count, each: 3 vertex ids, each minus the previous one (signed; the first
//     minus 0);
//   moved vertices: count, each: id (ascending, difference coded), its offset along its held normal
//     in grid steps minus the previous moved vertex's (signed), position minus the held one moved
//     by that offset (3 signed), normal code minus the held one's (2 signed).
#include "protocol/delta_v2.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <map>
#include <optional>
#include <string>
#include <unordered_map>
#include <unordered_set>

#include "protocol/delta_v2_geometry.h"
#include "protocol/range_coder.h"
#include "protocol/split_inference.h"

namespace isomesh::protocol {
namespace {

using Corners = HeldMesh::Corners;

Error frame_error(std::string message) {
    return Error{ErrorCode::bad_frame, std::move(message)};
}
Error field_error(std::string message) {
    return Error{ErrorCode::bad_field, std::move(message)};
}

/// The adaptive contexts of a delta body; encoder and decoder start from the same state.
struct Models {
    IntModel count;
    IntModel split_gap;
    BitModel edge_mispredicted;
    BitModel edge_second;
    IntModel position;
    IntModel normal;
    IntModel removed_gap;
    IntModel vertex_step;
    IntModel moved_gap;
    IntModel moved_offset;
    IntModel moved_position;
    IntModel moved_normal;
};

/// The edge a split most likely bisects: the one opposite the triangle's newest (largest id)
/// corner, the base edge of newest vertex bisection. Edge e joins corners e and e + 1.
int predicted_edge(const Corners& c) {
    const int newest = c[0] > c[1] ? (c[0] > c[2] ? 0 : 2) : (c[1] > c[2] ? 1 : 2);
    return (newest + 1) % 3;
}

/// The client's mesh as a delta changes it: the held mesh with changes on top, copied per vertex
/// star on first touch. The encoder and the decoder run the same operations on it.
class Overlay {
  public:
    explicit Overlay(const HeldMesh& held) : held_(held) {}

    const Corners* triangle(std::uint64_t id) const {
        if (auto it = created_.find(id); it != created_.end()) return &it->second;
        if (removed_.contains(id)) return nullptr;
        return held_.triangle(id);
    }
    const Vertex* vertex(std::uint32_t id) const {
        if (auto it = vertices_.find(id); it != vertices_.end()) return &it->second;
        return held_.vertex(id);
    }
    std::span<const std::uint64_t> star(std::uint32_t v) const {
        if (auto it = stars_.find(v); it != stars_.end()) return it->second;
        return held_.star(v);
    }
    /// The triangle holding the directed edge p -> q, if any; where several do (a non-manifold
    /// edge), the one with the smallest id, whatever the order of the star.
    std::optional<std::uint64_t> holding(std::uint32_t p, std::uint32_t q) const {
        std::optional<std::uint64_t> found;
        for (std::uint64_t id : star(p)) {
            const Corners& c = *triangle(id);
            for (int k = 0; k < 3; ++k) {
                if (c[k] == p && c[(k + 1) % 3] == q && (!found || id < *found)) found = id;
            }
        }
        return found;
    }
    void remove(std::uint64_t id) {
        const Corners c = *triangle(id);
        for (std::uint32_t v : c) std::erase(star_mut(v), id);
        if (created_.erase(id) == 0) removed_.insert(id);
    }
    void add(std::uint64_t id, const Corners& c) {
        created_.emplace(id, c);
        for (std::uint32_t v : c) star_mut(v).push_back(id);
    }
    void set_vertex(const Vertex& v) { vertices_[v.id] = v; }
    /// Room for `n` more vertex values (a frame that moves every vertex sets tens of thousands),
    /// at most as many as the held mesh has.
    void reserve_vertices(std::size_t n) {
        vertices_.reserve(vertices_.size() + std::min(n, held_.vertex_count()));
    }
    /// Whether triangle `id` was held or made in this frame (ids are never reused).
    bool used(std::uint64_t id) const { return created_.contains(id) || held_.triangle(id); }

    /// Bisects edge e of triangle t (and the triangle across it) at the new vertex v: (p, q, r)
    /// becomes (p, v, r) and (v, q, r); (q, p, s) becomes (q, v, s) and (v, p, s). The halves get
    /// ids from next_id on, in that order.
    void split(std::uint64_t t, int e, std::uint32_t v, std::uint64_t& next_id) {
        const Corners c = *triangle(t);
        const std::uint32_t p = c[e], q = c[(e + 1) % 3], r = c[(e + 2) % 3];
        const std::optional<std::uint64_t> across = holding(q, p);
        remove(t);
        add(next_id++, {p, v, r});
        add(next_id++, {v, q, r});
        if (!across) return;
        const Corners d = *triangle(*across);
        const int k = d[0] == q ? 0 : d[1] == q ? 1 : 2;
        const std::uint32_t s = d[(k + 2) % 3];
        remove(*across);
        add(next_id++, {q, v, s});
        add(next_id++, {v, p, s});
    }

    /// What the client ends with: held triangles removed, the live triangles made, and the values
    /// of every vertex those use and of `moved`.
    DecodedFrame result(const FrameHeader& header, std::span<const std::uint32_t> moved) const {
        DecodedFrame out;
        out.header = header;
        out.removed.assign(removed_.begin(), removed_.end());
        std::sort(out.removed.begin(), out.removed.end());
        for (const auto& [id, c] : created_) out.triangles.push_back({id, c});
        std::sort(out.triangles.begin(), out.triangles.end(),
                  [](const FrameTriangle& a, const FrameTriangle& b) { return a.id < b.id; });
        std::unordered_set<std::uint32_t> listed;
        listed.reserve(3 * out.triangles.size() + moved.size());
        out.vertices.reserve(listed.bucket_count());
        auto list = [&](std::uint32_t id) {
            if (listed.insert(id).second) out.vertices.push_back(*vertex(id));
        };
        for (const FrameTriangle& t : out.triangles) {
            for (std::uint32_t v : t.vertices) list(v);
        }
        for (std::uint32_t v : moved) list(v);
        out.header.removed_count = static_cast<std::uint32_t>(out.removed.size());
        out.header.triangle_count = static_cast<std::uint32_t>(out.triangles.size());
        return out;
    }

    const std::unordered_map<std::uint64_t, Corners>& created() const { return created_; }
    const std::unordered_set<std::uint64_t>& removed() const { return removed_; }

  private:
    std::vector<std::uint64_t>& star_mut(std::uint32_t v) {
        auto [it, added] = stars_.try_emplace(v);
        if (added) {
            const auto held = held_.star(v);
            it->second.assign(held.begin(), held.end());
        }
        return it->second;
    }

    const HeldMesh& held_;
    std::unordered_map<std::uint64_t, Corners> created_;
    std::unordered_set<std::uint64_t> removed_;
    std::unordered_map<std::uint32_t, std::vector<std::uint64_t>> stars_;
    std::unordered_map<std::uint32_t, Vertex> vertices_;
};

// ---- encoding ---------------------------------------------------------------------------------

/// The whole grid steps along `normal` from `from` nearest to `to`: (to - from) . normal, rounded,
/// within the bound a decoder accepts (PROTOCOL.md 4.5.2).
std::int64_t offset_along(const GridPoint& from, const glm::vec3& normal, const GridPoint& to) {
    double along = 0.0;
    for (int axis = 0; axis < 3; ++axis)
        along += static_cast<double>(to[axis] - from[axis]) * static_cast<double>(normal[axis]);
    return static_cast<std::int64_t>(std::floor(along + 0.5));
}

/// A split as the frame says it, in final ids.
struct PlannedSplit {
    std::size_t new_index;  // index into change.new_vertices
    std::uint32_t p, q;     // provisional or held ids
    int round = 0;
};

class DeltaEncoder {
  public:
    DeltaEncoder(const HeldMesh& held, const DeltaV2Change& change, std::uint64_t base_triangle,
                 std::uint32_t base_vertex, const QuantizationGrid& grid)
        : held_(held),
          change_(change),
          grid_(grid),
          overlay_(held),
          next_triangle_(base_triangle),
          base_vertex_(base_vertex),
          next_vertex_(base_vertex) {}

    Result<EncodedDeltaV2> encode(const FrameInfo& info);

  private:
    std::optional<Error> check() const;
    glm::vec3 position_of(std::uint32_t id) const;
    std::vector<PlannedSplit> plan_splits();
    void emit_splits(std::vector<PlannedSplit> splits);
    Vertex quantized(std::uint32_t id, const Vertex& v, GridPoint& q, OctNormal& n) const;
    std::uint32_t final_id(std::uint32_t id) const {
        auto it = final_.find(id);
        return it == final_.end() ? id : it->second;
    }
    void emit_explicit();
    void emit_moved();

    const HeldMesh& held_;
    const DeltaV2Change& change_;
    GridMath grid_;
    Overlay overlay_;
    RangeEncoder coder_;
    Models models_;
    std::uint64_t next_triangle_;
    std::uint32_t base_vertex_;
    std::uint32_t next_vertex_;
    std::unordered_map<std::uint32_t, std::uint32_t> final_;  // provisional -> final vertex id
    std::vector<std::uint32_t> loose_;                        // indices into new_vertices
    EncodedDeltaV2 out_;
};

std::optional<Error> DeltaEncoder::check() const {
    for (std::size_t i = 0; i < change_.new_vertices.size(); ++i) {
        if (change_.new_vertices[i].id != base_vertex_ + i)
            return field_error("new vertices must have ids base_vertex_id + i");
    }
    if (change_.new_vertices.size() > kMaxFrameTriangles ||
        change_.added.size() > kMaxFrameTriangles || change_.removed.size() > kMaxFrameTriangles)
        return field_error("more than 2^22 changes in one frame");
    for (std::uint64_t id : change_.removed) {
        if (!held_.triangle(id)) return field_error("removes a triangle the client lacks");
    }
    const std::uint64_t new_end = std::uint64_t{base_vertex_} + change_.new_vertices.size();
    for (const Triangle& t : change_.added) {
        for (std::uint32_t v : t.vertices) {
            if (!(v >= base_vertex_ && v < new_end) && !held_.vertex(v))
                return field_error("a triangle uses vertex " + std::to_string(v) +
                                   ", which is neither held nor new");
        }
    }
    for (const Vertex& v : change_.moved_vertices) {
        if (!held_.vertex(v.id)) return field_error("moves a vertex the client lacks");
    }
    return std::nullopt;
}

glm::vec3 DeltaEncoder::position_of(std::uint32_t id) const {
    if (id >= base_vertex_ && id - base_vertex_ < change_.new_vertices.size())
        return change_.new_vertices[id - base_vertex_].position;
    return held_.vertex(id)->position;
}

/// The splits in an order the client can replay: inferred newest-first, replayed oldest-first on
/// a scratch copy to learn each one's round (one more than the rounds that made its triangles).
std::vector<PlannedSplit> DeltaEncoder::plan_splits() {
    std::vector<std::uint32_t> new_ids;
    for (const Vertex& v : change_.new_vertices) new_ids.push_back(v.id);
    const SplitInference inferred =
        infer_splits(new_ids, change_.added, [this](std::uint32_t id) { return position_of(id); });
    for (std::uint32_t v : inferred.loose) loose_.push_back(v - base_vertex_);

    Overlay scratch(held_);
    std::unordered_map<std::uint64_t, int> round_made;  // scratch triangle id -> round
    std::uint64_t scratch_id = kMaxTriangleId + 1;      // apart from held ids
    std::vector<PlannedSplit> planned;
    for (const InferredSplit& s : inferred.splits) {
        const auto forward = scratch.holding(s.p, s.q);
        const auto backward = scratch.holding(s.q, s.p);
        if (!forward && !backward) {
            loose_.push_back(s.vertex - base_vertex_);
            continue;
        }
        int round = 0;
        for (const auto& t : {forward, backward}) {
            if (!t) continue;
            if (auto it = round_made.find(*t); it != round_made.end())
                round = std::max(round, it->second + 1);
        }
        const std::uint64_t t = forward ? *forward : *backward;
        const Corners& c = *scratch.triangle(t);
        const std::uint32_t from = forward ? s.p : s.q;
        const int e = c[0] == from ? 0 : c[1] == from ? 1 : 2;
        const std::uint64_t first = scratch_id;
        scratch.split(t, e, s.vertex, scratch_id);
        for (std::uint64_t id = first; id < scratch_id; ++id) round_made[id] = round;
        planned.push_back({s.vertex - base_vertex_, s.p, s.q, round});
    }
    std::sort(loose_.begin(), loose_.end());
    return planned;
}

Vertex DeltaEncoder::quantized(std::uint32_t id, const Vertex& v, GridPoint& q,
                               OctNormal& n) const {
    q = grid_.quantize(v.position);
    n = grid_.encode_normal(glm::dvec3(v.normal));
    return Vertex{id, grid_.dequantize(q), grid_.decode_normal(n)};
}

void DeltaEncoder::emit_splits(std::vector<PlannedSplit> splits) {
    std::stable_sort(
        splits.begin(), splits.end(),
        [](const PlannedSplit& a, const PlannedSplit& b) { return a.round < b.round; });
    const int rounds = splits.empty() ? 0 : splits.back().round + 1;
    coder_.charge_to(&out_.stats.split_reference_bits);
    coder_.uint(models_.count, static_cast<std::uint64_t>(rounds));
    std::size_t begin = 0;
    for (int round = 0; round < rounds; ++round) {
        std::size_t end = begin;
        while (end < splits.size() && splits[end].round == round) ++end;
        // Each split of the round names the smaller id of the (one or two) triangles holding its
        // edge, as the round starts: the round's splits touch distinct triangles.
        struct Named {
            std::uint64_t triangle;
            int edge;
            const PlannedSplit* split;
        };
        std::vector<Named> named;
        for (std::size_t i = begin; i < end; ++i) {
            const PlannedSplit& s = splits[i];
            const std::uint32_t p = final_id(s.p), q = final_id(s.q);
            const auto forward = overlay_.holding(p, q);
            const auto backward = overlay_.holding(q, p);
            const bool use_forward = forward && (!backward || *forward < *backward);
            const std::uint64_t t = use_forward ? *forward : *backward;
            const Corners& c = *overlay_.triangle(t);
            const std::uint32_t from = use_forward ? p : q;
            named.push_back({t, c[0] == from ? 0 : c[1] == from ? 1 : 2, &s});
        }
        std::sort(named.begin(), named.end(),
                  [](const Named& a, const Named& b) { return a.triangle < b.triangle; });
        coder_.charge_to(&out_.stats.split_reference_bits);
        coder_.uint(models_.count, named.size());
        std::uint64_t previous = 0;
        bool first = true;
        for (const Named& n : named) {
            coder_.charge_to(&out_.stats.split_reference_bits);
            coder_.uint(models_.split_gap, n.triangle - previous - (first ? 0 : 1));
            previous = n.triangle;
            first = false;
            const Corners c = *overlay_.triangle(n.triangle);
            const int miss = (n.edge - predicted_edge(c) + 3) % 3;
            coder_.bit(models_.edge_mispredicted, miss != 0);
            if (miss != 0) coder_.bit(models_.edge_second, miss == 2);

            const Vertex& input = change_.new_vertices[n.split->new_index];
            const std::uint32_t id = next_vertex_++;
            GridPoint q;
            OctNormal normal;
            const Vertex vertex = quantized(id, input, q, normal);
            const Vertex& a = *overlay_.vertex(c[n.edge]);
            const Vertex& b = *overlay_.vertex(c[(n.edge + 1) % 3]);
            const GridPoint predicted = grid_.predict_split(
                grid_.recover(a.position), grid_.recover(b.position), a.normal, b.normal);
            coder_.charge_to(&out_.stats.position_bits);
            for (int axis = 0; axis < 3; ++axis)
                coder_.sint(models_.position, q[axis] - predicted[axis]);
            const OctNormal predicted_normal = grid_.predict_normal(a.normal, b.normal);
            coder_.charge_to(&out_.stats.normal_bits);
            for (int k = 0; k < 2; ++k)
                coder_.sint(models_.normal, normal[k] - predicted_normal[k]);
            overlay_.set_vertex(vertex);
            overlay_.split(n.triangle, n.edge, id, next_triangle_);
            final_[input.id] = id;
            out_.vertex_ids[n.split->new_index] = id;
        }
        out_.stats.splits += named.size();
        begin = end;
    }
    out_.stats.rounds = static_cast<std::size_t>(rounds);
}

/// What the splits did not say: removals, loose vertices and added triangles, so that the client
/// ends with exactly the change's mesh.
void DeltaEncoder::emit_explicit() {
    coder_.charge_to(&out_.stats.explicit_bits);
    // Loose vertices get their ids now (after the splits'), so the targets below use final ids.
    for (std::uint32_t index : loose_) {
        final_[change_.new_vertices[index].id] = next_vertex_;
        out_.vertex_ids[index] = next_vertex_++;
    }
    std::map<Corners, std::size_t> wanted;  // canonical corners -> index in change.added
    for (std::size_t i = 0; i < change_.added.size(); ++i) {
        const Corners& c = change_.added[i].vertices;
        wanted[canonical_rotation({final_id(c[0]), final_id(c[1]), final_id(c[2])})] = i;
    }
    std::vector<std::uint64_t> removals;
    std::vector<bool> matched(change_.added.size(), false);
    for (const auto& [id, c] : overlay_.created()) {
        auto it = wanted.find(canonical_rotation(c));
        if (it != wanted.end() && !matched[it->second]) {
            matched[it->second] = true;
            out_.triangle_ids[it->second] = id;
        } else {
            removals.push_back(id);
        }
    }
    const std::unordered_set<std::uint64_t> target_removed(change_.removed.begin(),
                                                           change_.removed.end());
    for (std::uint64_t id : change_.removed) {
        if (!overlay_.removed().contains(id)) removals.push_back(id);
    }
    std::vector<std::pair<std::uint64_t, Corners>> additions;  // held triangles to bring back
    for (std::uint64_t id : overlay_.removed()) {
        if (!target_removed.contains(id)) additions.emplace_back(id, *held_.triangle(id));
    }
    std::sort(additions.begin(), additions.end());

    std::sort(removals.begin(), removals.end());
    coder_.uint(models_.count, removals.size());
    std::uint64_t previous = 0;
    for (std::size_t i = 0; i < removals.size(); ++i) {
        coder_.uint(models_.removed_gap, removals[i] - previous - (i == 0 ? 0 : 1));
        previous = removals[i];
        overlay_.remove(removals[i]);
    }
    coder_.uint(models_.count, loose_.size());
    for (std::uint32_t index : loose_) {
        GridPoint q;
        OctNormal n;
        const Vertex v = quantized(out_.vertex_ids[index], change_.new_vertices[index], q, n);
        for (int axis = 0; axis < 3; ++axis)
            coder_.direct(static_cast<std::uint32_t>(q[axis]), grid_.position_bits());
        for (int k = 0; k < 2; ++k)
            coder_.direct(static_cast<std::uint32_t>(n[k] + grid_.max_octahedral()),
                          grid_.normal_bits());
        overlay_.set_vertex(v);
    }
    std::vector<std::pair<Corners, std::optional<std::size_t>>> triangles;  // corners, added index
    for (const auto& [old_id, c] : additions) triangles.emplace_back(c, std::nullopt);
    for (std::size_t i = 0; i < change_.added.size(); ++i) {
        if (matched[i]) continue;
        const Corners& c = change_.added[i].vertices;
        triangles.emplace_back(Corners{final_id(c[0]), final_id(c[1]), final_id(c[2])}, i);
    }
    coder_.uint(models_.count, triangles.size());
    std::int64_t last = 0;
    for (std::size_t i = 0; i < triangles.size(); ++i) {
        const auto& [c, index] = triangles[i];
        for (std::uint32_t v : c) {
            coder_.sint(models_.vertex_step, static_cast<std::int64_t>(v) - last);
            last = v;
        }
        const std::uint64_t id = next_triangle_++;
        overlay_.add(id, c);
        if (index) {
            out_.triangle_ids[*index] = id;
        } else {
            out_.renamed.emplace_back(additions[i].first, id);
        }
    }
    out_.stats.loose_vertices = loose_.size();
    out_.stats.explicit_removed = removals.size();
    out_.stats.explicit_added = triangles.size();
}

void DeltaEncoder::emit_moved() {
    coder_.charge_to(&out_.stats.moved_bits);
    std::vector<const Vertex*> moved;
    for (const Vertex& v : change_.moved_vertices) moved.push_back(&v);
    std::sort(moved.begin(), moved.end(),
              [](const Vertex* a, const Vertex* b) { return a->id < b->id; });
    coder_.uint(models_.count, moved.size());
    overlay_.reserve_vertices(moved.size());
    std::uint64_t previous = 0;
    std::int64_t previous_offset = 0;
    for (std::size_t i = 0; i < moved.size(); ++i) {
        const Vertex& held = *overlay_.vertex(moved[i]->id);
        coder_.uint(models_.moved_gap, moved[i]->id - previous - (i == 0 ? 0 : 1));
        previous = moved[i]->id;
        GridPoint q;
        OctNormal n;
        const Vertex v = quantized(moved[i]->id, *moved[i], q, n);
        const GridPoint before = grid_.recover(held.position);
        // A surface that moves with a parameter moves along its normals: one offset says most of
        // it, and neighbouring vertices (close ids) move alike.
        const std::int64_t offset = offset_along(before, held.normal, q);
        coder_.sint(models_.moved_offset, offset - previous_offset);
        previous_offset = offset;
        const GridPoint predicted = grid_.predict_move(before, held.normal, offset);
        for (int axis = 0; axis < 3; ++axis)
            coder_.sint(models_.moved_position, q[axis] - predicted[axis]);
        const OctNormal before_normal = grid_.encode_normal(glm::dvec3(held.normal));
        for (int k = 0; k < 2; ++k) coder_.sint(models_.moved_normal, n[k] - before_normal[k]);
        overlay_.set_vertex(v);
    }
    out_.stats.moved = moved.size();
}

Result<EncodedDeltaV2> DeltaEncoder::encode(const FrameInfo& info) {
    if (auto error = check()) return *error;
    out_.triangle_ids.assign(change_.added.size(), 0);
    out_.vertex_ids.assign(change_.new_vertices.size(), 0);
    FrameHeader header;
    static_cast<FrameInfo&>(header) = info;
    header.base_triangle_id = next_triangle_;
    header.base_vertex_id = base_vertex_;
    emit_splits(plan_splits());
    emit_explicit();
    emit_moved();
    coder_.charge_to(nullptr);
    if (next_triangle_ - 1 > kMaxTriangleId)
        return field_error("triangle ids would exceed 2^53 - 1");
    if (next_vertex_ < base_vertex_) return field_error("vertex ids would exceed 2^32 - 1");

    out_.bytes.resize(kDeltaV2HeaderBytes);
    write_delta_v2_header(header, std::span<std::uint8_t, kDeltaV2HeaderBytes>(out_.bytes));
    const std::vector<std::uint8_t> body = coder_.finish();
    out_.bytes.insert(out_.bytes.end(), body.begin(), body.end());
    std::vector<std::uint32_t> moved_ids;
    for (const Vertex& v : change_.moved_vertices) moved_ids.push_back(v.id);
    out_.applied = overlay_.result(header, moved_ids);
    out_.next_triangle_id = next_triangle_;
    out_.next_vertex_id = next_vertex_;
    return std::move(out_);
}

// ---- decoding ---------------------------------------------------------------------------------

class DeltaDecoder {
  public:
    DeltaDecoder(const HeldMesh& held, const FrameHeader& header,
                 std::span<const std::uint8_t> body, const QuantizationGrid& grid)
        : header_(header),
          grid_(grid),
          overlay_(held),
          coder_(body),
          next_triangle_(header.base_triangle_id),
          next_vertex_(header.base_vertex_id) {}

    Result<DecodedFrame> decode();

  private:
    std::optional<Error> count(std::uint64_t& n);
    std::optional<Error> splits();
    std::optional<Error> removals();
    std::optional<Error> loose_vertices();
    std::optional<Error> triangles();
    std::optional<Error> moved();
    /// A triangle id the frame may give: below 2^53 and never used (a fuzzed base triangle id
    /// reused a held one, and the stars then named triangles that were gone).
    std::optional<Error> fresh_triangle_id(std::uint64_t id) const {
        if (id > kMaxTriangleId) return frame_error("triangle ids exceed 2^53 - 1");
        if (overlay_.used(id))
            return frame_error("new triangle " + std::to_string(id) + " reuses an id");
        return std::nullopt;
    }
    /// The next new vertex's id; one the mesh already has would make a split's halves degenerate
    /// (a fuzzed base vertex id did: the stars then named triangles that were gone).
    std::optional<Error> new_vertex_id(std::uint32_t& id) {
        if (next_vertex_ == UINT32_MAX) return frame_error("vertex ids exceed 2^32 - 1");
        if (overlay_.vertex(next_vertex_))
            return frame_error("new vertex " + std::to_string(next_vertex_) + " is already held");
        id = next_vertex_++;
        return std::nullopt;
    }

    FrameHeader header_;
    GridMath grid_;
    Overlay overlay_;
    RangeDecoder coder_;
    Models models_;
    std::uint64_t next_triangle_;
    std::uint32_t next_vertex_;
    std::vector<std::uint32_t> moved_;
};

std::optional<Error> DeltaDecoder::count(std::uint64_t& n) {
    n = coder_.uint(models_.count);
    if (!coder_.ok()) return frame_error("delta body is truncated or malformed");
    if (n > kMaxFrameTriangles) return frame_error("more than 2^22 changes in one frame");
    return std::nullopt;
}

std::optional<Error> DeltaDecoder::splits() {
    std::uint64_t rounds = 0;
    if (auto error = count(rounds)) return error;
    std::uint64_t total = 0;
    for (std::uint64_t round = 0; round < rounds; ++round) {
        std::uint64_t n = 0;
        if (auto error = count(n)) return error;
        if ((total += n) > kMaxFrameTriangles) return frame_error("more than 2^22 splits");
        std::uint64_t previous = 0;
        for (std::uint64_t i = 0; i < n; ++i) {
            const std::uint64_t gap = coder_.uint(models_.split_gap);
            const std::uint64_t t = previous + gap + (i == 0 ? 0 : 1);
            if (!coder_.ok() || t < previous || t > kMaxTriangleId)
                return frame_error("bad split triangle id");
            previous = t;
            const Corners* found = overlay_.triangle(t);
            if (!found) return frame_error("split of triangle " + std::to_string(t) + ", not held");
            const Corners c = *found;
            int miss = coder_.bit(models_.edge_mispredicted) ? 1 : 0;
            if (miss != 0 && coder_.bit(models_.edge_second)) miss = 2;
            const int e = (predicted_edge(c) + miss) % 3;
            const Vertex& a = *overlay_.vertex(c[e]);
            const Vertex& b = *overlay_.vertex(c[(e + 1) % 3]);
            GridPoint q = grid_.predict_split(grid_.recover(a.position), grid_.recover(b.position),
                                              a.normal, b.normal);
            for (int axis = 0; axis < 3; ++axis) q[axis] += coder_.sint(models_.position);
            OctNormal normal = grid_.predict_normal(a.normal, b.normal);
            for (int k = 0; k < 2; ++k) normal[k] += coder_.sint(models_.normal);
            if (!coder_.ok() || !grid_.valid(q) || !grid_.valid(normal))
                return frame_error("split vertex off the grid");
            std::uint32_t id = 0;
            if (auto error = new_vertex_id(id)) return error;
            for (std::uint64_t k = 0; k < 4; ++k) {
                if (auto error = fresh_triangle_id(next_triangle_ + k)) return error;
            }
            overlay_.set_vertex({id, grid_.dequantize(q), grid_.decode_normal(normal)});
            overlay_.split(t, e, id, next_triangle_);
        }
    }
    return std::nullopt;
}

std::optional<Error> DeltaDecoder::removals() {
    std::uint64_t n = 0;
    if (auto error = count(n)) return error;
    std::uint64_t previous = 0;
    for (std::uint64_t i = 0; i < n; ++i) {
        const std::uint64_t id = previous + coder_.uint(models_.removed_gap) + (i == 0 ? 0 : 1);
        if (!coder_.ok() || id < previous) return frame_error("bad removed triangle id");
        previous = id;
        if (!overlay_.triangle(id))
            return frame_error("removes triangle " + std::to_string(id) + ", not held");
        overlay_.remove(id);
    }
    return std::nullopt;
}

std::optional<Error> DeltaDecoder::loose_vertices() {
    std::uint64_t n = 0;
    if (auto error = count(n)) return error;
    for (std::uint64_t i = 0; i < n; ++i) {
        GridPoint q{};
        OctNormal normal{};
        for (int axis = 0; axis < 3; ++axis) q[axis] = coder_.direct(grid_.position_bits());
        for (int k = 0; k < 2; ++k)
            normal[k] = static_cast<std::int64_t>(coder_.direct(grid_.normal_bits())) -
                        grid_.max_octahedral();
        if (!coder_.ok() || !grid_.valid(q) || !grid_.valid(normal))
            return frame_error("loose vertex off the grid");
        std::uint32_t id = 0;
        if (auto error = new_vertex_id(id)) return error;
        overlay_.set_vertex({id, grid_.dequantize(q), grid_.decode_normal(normal)});
    }
    return std::nullopt;
}

std::optional<Error> DeltaDecoder::triangles() {
    std::uint64_t n = 0;
    if (auto error = count(n)) return error;
    std::int64_t last = 0;
    for (std::uint64_t i = 0; i < n; ++i) {
        Corners c{};
        for (auto& v : c) {
            const std::int64_t id = last + coder_.sint(models_.vertex_step);
            if (!coder_.ok() || id < 0 || id > INT64_C(0xFFFFFFFF))
                return frame_error("bad vertex id");
            v = static_cast<std::uint32_t>(id);
            last = id;
            if (!overlay_.vertex(v))
                return frame_error("a triangle uses unknown vertex " + std::to_string(v));
        }
        if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2])
            return frame_error("a triangle repeats a vertex");
        if (auto error = fresh_triangle_id(next_triangle_)) return error;
        overlay_.add(next_triangle_++, c);
    }
    return std::nullopt;
}

std::optional<Error> DeltaDecoder::moved() {
    std::uint64_t n = 0;
    if (auto error = count(n)) return error;
    overlay_.reserve_vertices(n);
    std::uint64_t previous = 0;
    std::int64_t offset = 0;
    const std::int64_t max_offset = 2 * grid_.max_coordinate() + 2;
    for (std::uint64_t i = 0; i < n; ++i) {
        const std::uint64_t id = previous + coder_.uint(models_.moved_gap) + (i == 0 ? 0 : 1);
        if (!coder_.ok() || id < previous || id > UINT32_MAX)
            return frame_error("bad moved vertex id");
        previous = id;
        const Vertex* held = overlay_.vertex(static_cast<std::uint32_t>(id));
        if (!held) return frame_error("moves vertex " + std::to_string(id) + ", not held");
        offset += coder_.sint(models_.moved_offset);
        if (!coder_.ok() || offset < -max_offset || offset > max_offset)
            return frame_error("moved vertex offset out of range");
        GridPoint q = grid_.predict_move(grid_.recover(held->position), held->normal, offset);
        OctNormal normal = grid_.encode_normal(glm::dvec3(held->normal));
        for (int axis = 0; axis < 3; ++axis) q[axis] += coder_.sint(models_.moved_position);
        for (int k = 0; k < 2; ++k) normal[k] += coder_.sint(models_.moved_normal);
        if (!coder_.ok() || !grid_.valid(q) || !grid_.valid(normal))
            return frame_error("moved vertex off the grid");
        overlay_.set_vertex(
            {static_cast<std::uint32_t>(id), grid_.dequantize(q), grid_.decode_normal(normal)});
        moved_.push_back(static_cast<std::uint32_t>(id));
    }
    return std::nullopt;
}

Result<DecodedFrame> DeltaDecoder::decode() {
    if (!coder_.ok()) return frame_error("delta body shorter than 5 bytes or not starting with 0");
    for (auto step : {&DeltaDecoder::splits, &DeltaDecoder::removals, &DeltaDecoder::loose_vertices,
                      &DeltaDecoder::triangles, &DeltaDecoder::moved}) {
        if (auto error = (this->*step)()) return *error;
    }
    return overlay_.result(header_, moved_);
}

}  // namespace

Result<EncodedDeltaV2> encode_delta_v2(const FrameInfo& info, const HeldMesh& held,
                                       const DeltaV2Change& change, std::uint64_t base_triangle_id,
                                       std::uint32_t base_vertex_id, const QuantizationGrid& grid) {
    assert(info.kind == FrameKind::delta && info.protocol_version == 2);
    DeltaEncoder encoder(held, change, base_triangle_id, base_vertex_id, grid);
    return encoder.encode(info);
}

Result<DecodedFrame> decode_delta_v2(std::span<const std::uint8_t> frame, const HeldMesh& held,
                                     const QuantizationGrid& grid) {
    auto header = read_frame_header(frame);
    if (!header) return header.error();
    if (header.value().protocol_version != 2 || header.value().kind != FrameKind::delta)
        return frame_error("not a version-2 delta");
    DeltaDecoder decoder(held, header.value(), frame.subspan(kDeltaV2HeaderBytes), grid);
    return decoder.decode();
}

}  // namespace isomesh::protocol
