// Writing meshes to files: PLY (binary little endian) and Wavefront OBJ, both with normals.
#pragma once

#include <iosfwd>
#include <string>

#include "mesh/mesh.h"

namespace isomesh {

/// PLY 1.0, binary_little_endian: vertices as float x y z nx ny nz (normals present only when
/// mesh.normals has one per vertex), faces as a uchar count and int indices. Throws
/// std::runtime_error when the stream fails.
void write_ply(const Mesh& mesh, std::ostream& out);

/// OBJ: `v x y z`, `vn nx ny nz` (when mesh.normals has one per vertex) and `f a//a b//b c//c`
/// (1-based), coordinates with 17 significant digits so they read back exactly. Throws
/// std::runtime_error when the stream fails.
void write_obj(const Mesh& mesh, std::ostream& out);

/// Writes `path` in the format its extension names (.ply or .obj, any letter case). Throws
/// std::runtime_error for another extension or when the file cannot be written.
void write_mesh_file(const Mesh& mesh, const std::string& path);

}  // namespace isomesh
