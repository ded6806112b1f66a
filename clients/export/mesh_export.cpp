// glTF 2.0 binary with KHR_draco_mesh_compression, and binary STL, through Draco's encoders.
#include "mesh_export.h"

#include <algorithm>
#include <cassert>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>

#include <draco/io/gltf_encoder.h>
#include <draco/io/stl_encoder.h>
#include <draco/mesh/mesh.h>
#include <glm/geometric.hpp>

#include "mesh/mesh_io.h"

namespace isomesh {
namespace {

/// ".glb" for "dir/Mesh.GLB"; "" when the file name has no extension.
std::string lower_extension(std::string_view path) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return ext;
}

void check(const draco::Status& status, std::string_view what) {
    if (!status.ok()) {
        throw std::runtime_error(std::string(what) + ": " + status.error_msg_string());
    }
}

/// Unit normals for every vertex: the mesh's own where it has a non-zero one, otherwise the sum
/// of the cross products of the faces around the vertex (each twice its face's area, so the sum
/// is area-weighted), or +z for a vertex no face with an area touches.
std::vector<glm::vec3> unit_normals(const Mesh& mesh) {
    const bool has_normals = mesh.normals.size() == mesh.positions.size();
    std::vector<glm::dvec3> sums(mesh.positions.size(), glm::dvec3(0.0));
    for (const auto& t : mesh.triangles) {
        const glm::dvec3 area_normal = glm::cross(mesh.positions[t[1]] - mesh.positions[t[0]],
                                                  mesh.positions[t[2]] - mesh.positions[t[0]]);
        for (std::uint32_t v : t) sums[v] += area_normal;
    }
    std::vector<glm::vec3> normals(mesh.positions.size());
    for (std::size_t v = 0; v < normals.size(); ++v) {
        glm::dvec3 n = has_normals ? mesh.normals[v] : glm::dvec3(0.0);
        if (!(glm::length(n) > 0.5)) n = sums[v];
        const double length = glm::length(n);
        normals[v] = length > 0.0 ? glm::vec3(n / length) : glm::vec3(0.0f, 0.0f, 1.0f);
    }
    return normals;
}

/// Adds a float32 x 3 attribute with one value per point and returns its id.
int add_vec3_attribute(draco::Mesh& out, draco::GeometryAttribute::Type type,
                       const std::vector<glm::vec3>& values) {
    auto attribute = std::make_unique<draco::PointAttribute>();
    attribute->Init(type, 3, draco::DT_FLOAT32, false, values.size());
    for (std::size_t i = 0; i < values.size(); ++i) {
        attribute->SetAttributeValue(draco::AttributeValueIndex(static_cast<std::uint32_t>(i)),
                                     &values[i].x);
    }
    return out.AddAttribute(std::move(attribute));
}

/// `mesh` as a Draco mesh with one point per vertex: positions, and normals when given.
std::unique_ptr<draco::Mesh> to_draco(const Mesh& mesh, const std::vector<glm::vec3>* normals) {
    auto out = std::make_unique<draco::Mesh>();
    out->set_num_points(static_cast<std::uint32_t>(mesh.positions.size()));
    std::vector<glm::vec3> positions(mesh.positions.begin(), mesh.positions.end());
    add_vec3_attribute(*out, draco::GeometryAttribute::POSITION, positions);
    if (normals) add_vec3_attribute(*out, draco::GeometryAttribute::NORMAL, *normals);
    out->SetNumFaces(mesh.triangles.size());
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
        const auto& t = mesh.triangles[f];
        assert(t[0] < mesh.vertex_count() && t[1] < mesh.vertex_count() &&
               t[2] < mesh.vertex_count());
        out->SetFace(draco::FaceIndex(static_cast<std::uint32_t>(f)),
                     {draco::PointIndex(t[0]), draco::PointIndex(t[1]), draco::PointIndex(t[2])});
    }
    return out;
}

std::vector<std::uint8_t> bytes_of(const draco::EncoderBuffer& buffer) {
    const auto* data = reinterpret_cast<const std::uint8_t*>(buffer.data());
    return std::vector<std::uint8_t>(data, data + buffer.size());
}

}  // namespace

std::vector<std::uint8_t> encode_glb(const Mesh& mesh, const GlbSettings& settings) {
    // (Not DracoCompressionOptions::Check(): inlined, it trips GCC 12's -Wrestrict false positive.)
    if (settings.position_bits < 1 || settings.position_bits > 30 || settings.normal_bits < 1 ||
        settings.normal_bits > 30 || settings.compression_level < 0 ||
        settings.compression_level > 10) {
        throw std::runtime_error("glb settings out of range");
    }
    const std::vector<glm::vec3> normals = unit_normals(mesh);
    std::unique_ptr<draco::Mesh> draco_mesh = to_draco(mesh, &normals);
    draco::DracoCompressionOptions options;
    options.compression_level = settings.compression_level;
    options.quantization_position.SetQuantizationBits(settings.position_bits);
    options.quantization_bits_normal = settings.normal_bits;
    draco_mesh->SetCompressionOptions(options);
    draco_mesh->SetCompressionEnabled(true);
    draco::GltfEncoder encoder;
    draco::EncoderBuffer buffer;
    check(encoder.EncodeToBuffer(*draco_mesh, &buffer), "glb encoding");
    return bytes_of(buffer);
}

std::vector<std::uint8_t> encode_stl(const Mesh& mesh) {
    std::unique_ptr<draco::Mesh> draco_mesh = to_draco(mesh, nullptr);
    draco::StlEncoder encoder;
    draco::EncoderBuffer buffer;
    check(encoder.EncodeToBuffer(*draco_mesh, &buffer), "stl encoding");
    return bytes_of(buffer);
}

bool is_export_file_name(std::string_view path) {
    const std::string ext = lower_extension(path);
    return ext == ".glb" || ext == ".stl" || ext == ".ply" || ext == ".obj";
}

void write_export_file(const Mesh& mesh, const std::string& path) {
    const std::string ext = lower_extension(path);
    if (!is_export_file_name(path)) {
        throw std::runtime_error("unsupported mesh file type '" + ext + "' for " + path +
                                 " (use .glb, .stl, .ply or .obj)");
    }
    if (ext == ".ply" || ext == ".obj") {
        write_mesh_file(mesh, path);
        return;
    }
    const std::vector<std::uint8_t> bytes = ext == ".glb" ? encode_glb(mesh) : encode_stl(mesh);
    std::ofstream out(path, std::ios::binary);
    if (!out) throw std::runtime_error("cannot open " + path + " for writing");
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
    out.close();
    if (!out) throw std::runtime_error("cannot write " + path);
}

}  // namespace isomesh
