#include "protocol/tools/octahedron.h"

#include "protocol/delta_v2_geometry.h"

namespace isomesh::protocol::samples {

QuantizationGrid octahedron_grid() {
    return QuantizationGrid::for_box({-1, 1, -1, 1, -1, 1});
}

HeldMesh octahedron() {
    const GridMath grid(octahedron_grid());
    const glm::vec3 corners[6] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                  {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
    DecodedFrame frame;
    frame.header.kind = FrameKind::keyframe;
    for (std::uint32_t v = 0; v < 6; ++v) {
        frame.vertices.push_back({v, grid.dequantize(grid.quantize(corners[v])),
                                  grid.decode_normal(grid.encode_normal(glm::dvec3(corners[v])))});
    }
    // Counter-clockwise seen from outside: (x, y, z) octant faces.
    const std::array<std::uint32_t, 3> faces[8] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                                                   {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
    for (std::uint64_t t = 0; t < 8; ++t) frame.triangles.push_back({t, faces[t]});
    HeldMesh mesh;
    mesh.apply(frame);
    return mesh;
}

}  // namespace isomesh::protocol::samples
