// Version-2 delta frames: the decoder (see delta_v2.h; the body's layout is described atop
// delta_v2.cpp and in PROTOCOL.md 4.5).
#include <optional>
#include <vector>

#include "protocol/delta_v2.h"
#include "protocol/delta_v2_geometry.h"
#include "protocol/delta_v2_overlay.h"
#include "protocol/range_coder.h"
#include "protocol/split_inference.h"

namespace isomesh::protocol {
namespace {

using namespace delta_v2_detail;

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
