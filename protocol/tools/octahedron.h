// A small closed mesh (the unit octahedron, 6 vertices, 8 triangles with ids 0..7) as a client
// holds it after a version-2 keyframe: the base of the version-2 delta tests and of the frame
// decoder fuzzer's version-2 inputs.
#pragma once

#include "protocol/held_mesh.h"

namespace isomesh::protocol::samples {

/// The grid of the box [-1, 1]^3.
QuantizationGrid octahedron_grid();
/// The octahedron on that grid, positions and normals as a client decodes them.
HeldMesh octahedron();

}  // namespace isomesh::protocol::samples
