// PLY (Turk, "The PLY polygon file format", 1994) and OBJ (Wavefront) writers.
#include "mesh/mesh_io.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <ostream>
#include <stdexcept>
#include <vector>

namespace isomesh {
namespace {

static_assert(std::endian::native == std::endian::little,
              "the PLY writer copies little-endian memory as it is");

bool has_normals(const Mesh& mesh) {
    return !mesh.positions.empty() && mesh.normals.size() == mesh.positions.size();
}

void check(const std::ostream& out, const std::string& what) {
    if (!out) throw std::runtime_error("cannot write " + what);
}

template <typename T>
void append(std::vector<char>& buffer, T value) {
    const auto bytes = std::bit_cast<std::array<char, sizeof(T)>>(value);
    buffer.insert(buffer.end(), bytes.begin(), bytes.end());
}

std::string lower_extension(const std::string& path) {
    const auto dot = path.find_last_of('.');
    const auto slash = path.find_last_of("/\\");
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
    std::string ext = path.substr(dot);
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return ext;
}

}  // namespace

void write_ply(const Mesh& mesh, std::ostream& out) {
    const bool normals = has_normals(mesh);
    out << "ply\nformat binary_little_endian 1.0\ncomment isomesh\n"
        << "element vertex " << mesh.positions.size() << "\n"
        << "property float x\nproperty float y\nproperty float z\n";
    if (normals) out << "property float nx\nproperty float ny\nproperty float nz\n";
    out << "element face " << mesh.triangles.size() << "\n"
        << "property list uchar int vertex_indices\nend_header\n";
    std::vector<char> buffer;
    buffer.reserve(mesh.positions.size() * 24 + mesh.triangles.size() * 13);
    for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
        for (int i = 0; i < 3; ++i) append(buffer, static_cast<float>(mesh.positions[v][i]));
        if (!normals) continue;
        for (int i = 0; i < 3; ++i) append(buffer, static_cast<float>(mesh.normals[v][i]));
    }
    for (const auto& triangle : mesh.triangles) {
        append(buffer, std::uint8_t{3});
        for (std::uint32_t v : triangle) append(buffer, static_cast<std::int32_t>(v));
    }
    out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    check(out, "PLY data");
}

void write_obj(const Mesh& mesh, std::ostream& out) {
    const bool normals = has_normals(mesh);
    char line[128];
    out << "# isomesh\n";
    for (const auto& p : mesh.positions) {
        std::snprintf(line, sizeof line, "v %.17g %.17g %.17g\n", p.x, p.y, p.z);
        out << line;
    }
    if (normals) {
        for (const auto& n : mesh.normals) {
            std::snprintf(line, sizeof line, "vn %.17g %.17g %.17g\n", n.x, n.y, n.z);
            out << line;
        }
    }
    for (const auto& t : mesh.triangles) {
        if (normals) {
            out << "f " << t[0] + 1 << "//" << t[0] + 1 << ' ' << t[1] + 1 << "//" << t[1] + 1
                << ' ' << t[2] + 1 << "//" << t[2] + 1 << '\n';
        } else {
            out << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
        }
    }
    check(out, "OBJ data");
}

void write_mesh_file(const Mesh& mesh, const std::string& path) {
    const std::string ext = lower_extension(path);
    if (ext != ".ply" && ext != ".obj") {
        throw std::runtime_error("unsupported mesh file type '" + ext + "' for " + path +
                                 " (use .ply or .obj)");
    }
    std::ofstream out(path, std::ios::binary);
    if (!out) throw std::runtime_error("cannot open " + path + " for writing");
    if (ext == ".ply") {
        write_ply(mesh, out);
    } else {
        write_obj(mesh, out);
    }
    out.close();
    check(out, path);
}

}  // namespace isomesh
