// libFuzzer target: the binary frame decoder (protocol/frame.h). Any input must give an error or a
// frame whose parts agree with its header, and that a replica can apply without crashing.
#include <cstdint>
#include <cstdlib>
#include <unordered_set>

#include "protocol/frame.h"
#include "protocol/replica.h"

using namespace isomesh::protocol;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
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
