// libFuzzer target: the binary frame decoders (protocol/frame.h, protocol/delta_v2.h). Any input
// must give an error or a frame whose parts agree with its header, and that a replica can apply
// without crashing. Version-2 deltas are decoded against a held octahedron (protocol/tools).
#include <cstdint>
#include <cstdlib>
#include <unordered_set>

#include "protocol/delta_v2.h"
#include "protocol/frame.h"
#include "protocol/replica.h"
#include "protocol/tools/octahedron.h"

using namespace isomesh::protocol;

namespace {

/// A version-2 delta decoded against the octahedron: every triangle it adds uses vertices it
/// lists, and the held mesh applies it.
void check_delta_v2(std::span<const std::uint8_t> bytes) {
    static const HeldMesh octahedron = samples::octahedron();
    auto decoded = decode_delta_v2(bytes, octahedron, samples::octahedron_grid());
    if (!decoded) return;
    std::unordered_set<std::uint32_t> vertices;
    for (const Vertex& v : decoded.value().vertices) vertices.insert(v.id);
    for (const FrameTriangle& t : decoded.value().triangles) {
        for (std::uint32_t v : t.vertices) {
            if (!vertices.contains(v)) std::abort();
        }
    }
    for (std::uint64_t id : decoded.value().removed) {
        if (!octahedron.triangle(id)) std::abort();
    }
    HeldMesh copy = octahedron;
    copy.apply(decoded.value());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    check_delta_v2(std::span<const std::uint8_t>(data, size));
    auto decoded = decode_frame(std::span<const std::uint8_t>(data, size));
    if (!decoded) return 0;
    const DecodedFrame& frame = decoded.value();
    if (frame.removed.size() != frame.header.removed_count ||
        frame.triangles.size() != frame.header.triangle_count) {
        std::abort();
    }
    std::unordered_set<std::uint32_t> vertices;
    for (const Vertex& v : frame.vertices) vertices.insert(v.id);
    for (const FrameTriangle& t : frame.triangles) {
        if (t.id > kMaxTriangleId) std::abort();
        for (std::uint32_t v : t.vertices) {
            if (!vertices.contains(v)) std::abort();
        }
    }
    MeshReplica replica;
    replica.apply(frame);
    return 0;
}
