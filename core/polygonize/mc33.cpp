// Marching Cubes 33 cell triangulation (see mc33.h for the papers and conventions).
// STUB: returns no triangles until the case tables land.
#include "polygonize/mc33.h"

namespace isomesh {

bool CellTriangulation::uses_interior_vertex() const {
    for (std::uint8_t t = 0; t < triangle_count; ++t) {
        for (std::uint8_t v : triangles[t]) {
            if (v == kInteriorVertex) return true;
        }
    }
    return false;
}

std::uint8_t corner_configuration(const std::array<double, 8>& corner_values) {
    std::uint8_t config = 0;
    for (int i = 0; i < 8; ++i) {
        if (corner_values[i] < 0.0) config |= static_cast<std::uint8_t>(1u << i);
    }
    return config;
}

CellTriangulation triangulate_cell(const std::array<double, 8>& corner_values) {
    (void)corner_values;
    return {};
}

}  // namespace isomesh
