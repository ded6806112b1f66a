// Comparing two meshes the way a client sees them: positions on a session's quantization grid
// (protocol/mesh_codec.h), whatever the vertex and triangle ids (which depend on how often a
// resolving phase 1 replaced the mesh, progressive/pipeline.h). Header-only, for the test
// folders that compare a server's mesh with the core's.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "mesh/mesh.h"
#include "protocol/mesh_codec.h"

namespace isomesh::test {

/// Empty when `got` is `want`: every vertex of `got` matches one of `want` within one grid step
/// on every axis (and, if normal_tolerance >= 0, normals within that distance where `want`'s is
/// a unit vector), and the triangles are the same with the same orientation. Otherwise the first
/// difference.
inline std::string compare_on_grid(const Mesh& got, const Mesh& want,
                                   const protocol::QuantizationGrid& grid,
                                   double normal_tolerance = -1.0) {
    const double step = grid.range / double((1 << grid.position_bits) - 1);
    auto cell = [&](const glm::dvec3& p) {
        std::array<std::int64_t, 3> q;
        for (int axis = 0; axis < 3; ++axis)
            q[axis] = std::llround((p[axis] - double(grid.origin[axis])) / step);
        return q;
    };
    std::map<std::array<std::int64_t, 3>, std::vector<std::uint32_t>> by_cell;
    for (std::uint32_t v = 0; v < want.positions.size(); ++v)
        by_cell[cell(want.positions[v])].push_back(v);
    std::vector<std::uint32_t> index_of(got.positions.size());
    for (std::uint32_t g = 0; g < got.positions.size(); ++g) {
        const glm::dvec3& p = got.positions[g];
        const auto q = cell(p);
        double best = step;
        std::optional<std::uint32_t> match;
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz) {
                    const auto it = by_cell.find({q[0] + dx, q[1] + dy, q[2] + dz});
                    if (it == by_cell.end()) continue;
                    for (std::uint32_t v : it->second) {
                        const glm::dvec3 d = glm::abs(want.positions[v] - p);
                        const double far = std::max({d.x, d.y, d.z});
                        if (far <= best) {
                            best = far;
                            match = v;
                        }
                    }
                }
        if (!match) return "vertex " + std::to_string(g) + " matches no vertex";
        index_of[g] = *match;
        if (normal_tolerance >= 0.0 && g < got.normals.size() &&
            glm::length(want.normals[*match]) > 0.5 &&
            glm::length(got.normals[g] - want.normals[*match]) > normal_tolerance)
            return "vertex " + std::to_string(g) + " has another normal";
    }
    auto rotated = [](std::array<std::uint32_t, 3> t) {
        const auto first = std::min_element(t.begin(), t.end()) - t.begin();
        return std::array<std::uint32_t, 3>{t[first], t[(first + 1) % 3], t[(first + 2) % 3]};
    };
    std::vector<std::array<std::uint32_t, 3>> mapped, expected;
    for (const auto& t : got.triangles)
        mapped.push_back(rotated({index_of[t[0]], index_of[t[1]], index_of[t[2]]}));
    for (const auto& t : want.triangles) expected.push_back(rotated(t));
    std::sort(mapped.begin(), mapped.end());
    std::sort(expected.begin(), expected.end());
    if (mapped.size() != expected.size())
        return std::to_string(mapped.size()) + " triangles instead of " +
               std::to_string(expected.size());
    const auto diff = std::mismatch(mapped.begin(), mapped.end(), expected.begin());
    if (diff.first != mapped.end())
        return "triangle " + std::to_string(diff.first - mapped.begin()) + " differs";
    return {};
}

}  // namespace isomesh::test
