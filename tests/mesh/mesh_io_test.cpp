#include "mesh/mesh_io.h"

#include <cstring>
#include <sstream>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

namespace isomesh {
namespace {

Mesh one_triangle() {
    Mesh mesh;
    mesh.positions = {{0.1, 0.0, 0.0}, {1.0, 0.0, 0.0}, {0.0, 1.0 / 3.0, 0.0}};
    mesh.normals = {{0.0, 0.0, 1.0}, {0.0, 0.0, 1.0}, {0.0, 0.0, 1.0}};
    mesh.triangles = {{0, 1, 2}};
    return mesh;
}

TEST(MeshIo, write_ply_is_binary_little_endian_with_normals) {
    std::ostringstream out;
    write_ply(one_triangle(), out);
    const std::string data = out.str();
    const std::string end = "end_header\n";
    const std::size_t body = data.find(end) + end.size();
    ASSERT_NE(body, std::string::npos + end.size());
    EXPECT_EQ(data.rfind("ply\nformat binary_little_endian 1.0\n", 0), 0u);
    ASSERT_EQ(data.size() - body, 3 * 24 + 13);
    float x1;
    std::memcpy(&x1, data.data() + body + 24, sizeof x1);
    EXPECT_EQ(x1, 1.0f);
    EXPECT_EQ(data[body + 72], 3);  // the face's vertex count
    std::int32_t last;
    std::memcpy(&last, data.data() + body + 72 + 1 + 8, sizeof last);
    EXPECT_EQ(last, 2);
}

TEST(MeshIo, write_ply_without_normals_leaves_them_out) {
    Mesh mesh = one_triangle();
    mesh.normals.clear();
    std::ostringstream out;
    write_ply(mesh, out);
    EXPECT_EQ(out.str().find("nx"), std::string::npos);
}

TEST(MeshIo, write_obj_keeps_every_digit_and_counts_from_one) {
    std::ostringstream out;
    write_obj(one_triangle(), out);
    std::istringstream in(out.str());
    std::string line;
    double y = 0.0;
    while (std::getline(in, line)) {
        if (line.rfind("v 0 0.33", 0) == 0) y = std::stod(line.substr(4));
        if (line.rfind("f ", 0) == 0) {
            EXPECT_EQ(line, "f 1//1 2//2 3//3");
        }
    }
    EXPECT_EQ(y, 1.0 / 3.0);
}

TEST(MeshIo, write_mesh_file_refuses_other_types_and_unwritable_paths) {
    EXPECT_THROW(write_mesh_file(one_triangle(), "/tmp/mesh.xyz"), std::runtime_error);
    EXPECT_THROW(write_mesh_file(one_triangle(), "/tmp/ply"), std::runtime_error);
    EXPECT_THROW(write_mesh_file(one_triangle(), "/nonexistent/dir/mesh.ply"), std::runtime_error);
}

}  // namespace
}  // namespace isomesh
