// Mesh files for other programs: glTF 2.0 binary (.glb) with Draco compression and binary STL,
// next to core's PLY and OBJ writers (mesh/mesh_io.h). Both new formats come from Draco's own
// encoders (draco/io/gltf_encoder.h, draco/io/stl_encoder.h), which is why this library lives
// outside core/: core depends on the standard library and GLM only.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "mesh/mesh.h"

namespace isomesh {

/// Draco quantization of a .glb: positions on a grid of 2^position_bits steps across the mesh's
/// bounding box (16 bits: 1/65535 of the box, well below a polygonizer cell), normals on the
/// octahedron with normal_bits.
struct GlbSettings {
    int position_bits = 16;     ///< 1..30
    int normal_bits = 12;       ///< 1..30
    int compression_level = 7;  ///< Draco's 0 (fastest) .. 10 (smallest)
};

/// A glTF 2.0 binary file (GLB) holding `mesh` as one triangle primitive with POSITION and NORMAL,
/// compressed with the KHR_draco_mesh_compression extension (declared required, so readers without
/// Draco refuse it instead of showing nothing). Normals the mesh lacks or has as zero (where the
/// gradient vanishes; glTF wants unit normals) are replaced by the area-weighted average of the
/// faces around the vertex. Preconditions: every triangle index < mesh.vertex_count() and
/// positions finite. Throws std::runtime_error when Draco fails.
std::vector<std::uint8_t> encode_glb(const Mesh& mesh, const GlbSettings& settings = {});

/// Binary STL: an 80-byte header, the triangle count, then per triangle its facet normal (from
/// its corners, counter-clockwise) and corners as float32. Same preconditions; throws
/// std::runtime_error when Draco fails.
std::vector<std::uint8_t> encode_stl(const Mesh& mesh);

/// True when `path` ends in an extension write_export_file knows: .glb, .stl, .ply or .obj
/// (any letter case).
bool is_export_file_name(std::string_view path);

/// Writes `path` in the format its extension names: .glb and .stl here, .ply and .obj through
/// mesh/mesh_io.h. Throws std::runtime_error for another extension or when the file cannot be
/// written.
void write_export_file(const Mesh& mesh, const std::string& path);

}  // namespace isomesh
