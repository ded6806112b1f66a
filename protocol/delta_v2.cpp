// Version-2 delta frames: the encoder (see delta_v2.h; layout in PROTOCOL.md 4.5; the decoder is
// delta_v2_decoder.cpp).
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
#include <optional>
#include <string>

#include <absl/container/flat_hash_set.h>

#include "protocol/delta_v2_geometry.h"
#include "protocol/delta_v2_overlay.h"
#include "protocol/range_coder.h"
#include "protocol/split_inference.h"

namespace isomesh::protocol {
namespace {

using namespace delta_v2_detail;

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
    IdTable<std::uint32_t, std::uint32_t> final_;  // provisional -> final vertex id
    std::vector<std::uint32_t> loose_;             // indices into new_vertices
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
    IdTable<std::uint64_t, int> round_made;         // scratch triangle id -> round
    std::uint64_t scratch_id = kMaxTriangleId + 1;  // apart from held ids
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
    IdTable<Corners, std::size_t> wanted;  // canonical corners -> index in change.added
    wanted.reserve(change_.added.size());
    for (std::size_t i = 0; i < change_.added.size(); ++i) {
        const Corners& c = change_.added[i].vertices;
        wanted[canonical_rotation({final_id(c[0]), final_id(c[1]), final_id(c[2])})] = i;
    }
    // The triangles the splits made, by id: which of two alike (a doubled triangle) matches must
    // not depend on the table's order.
    std::vector<std::pair<std::uint64_t, Corners>> created(overlay_.created().begin(),
                                                           overlay_.created().end());
    std::sort(created.begin(), created.end());
    std::vector<std::uint64_t> removals;
    std::vector<bool> matched(change_.added.size(), false);
    for (const auto& [id, c] : created) {
        auto it = wanted.find(canonical_rotation(c));
        if (it != wanted.end() && !matched[it->second]) {
            matched[it->second] = true;
            out_.triangle_ids[it->second] = id;
        } else {
            removals.push_back(id);
        }
    }
    const absl::flat_hash_set<std::uint64_t> target_removed(change_.removed.begin(),
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

}  // namespace

Result<EncodedDeltaV2> encode_delta_v2(const FrameInfo& info, const HeldMesh& held,
                                       const DeltaV2Change& change, std::uint64_t base_triangle_id,
                                       std::uint32_t base_vertex_id, const QuantizationGrid& grid) {
    assert(info.kind == FrameKind::delta && info.protocol_version == 2);
    DeltaEncoder encoder(held, change, base_triangle_id, base_vertex_id, grid);
    return encoder.encode(info);
}

}  // namespace isomesh::protocol
