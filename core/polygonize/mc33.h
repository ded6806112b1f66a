// Marching Cubes 33: the triangulation of one cell with the topology of the cell's trilinear
// interpolant (Chernyaev, "Marching Cubes 33: construction of topologically correct isosurfaces",
// CERN CN 95-17, 1995), with the face test of Nielson & Hamann ("The asymptotic decider", IEEE
// Visualization 1991) and the interior test of Lewiner et al. ("Efficient implementation of
// Marching Cubes' cases with topological guarantees", JGT 8(2), 2003) as corrected by Custodio et
// al. ("Practical considerations on Marching Cubes 33 topological correctness", Computers &
// Graphics 37(7), 2013).
//
// Cell conventions (fixed: the octree polygonizer and the uniform-grid mesher rely on them):
// - Corner i sits at offset (i & 1, (i >> 1) & 1, (i >> 2) & 1) from the cell's lowest corner
//   (x fastest).
// - Edges are grouped by axis: edges 0..3 run along x, at (y, z) offsets (0,0), (1,0), (0,1),
//   (1,1); edges 4..7 run along y, at (x, z) = (0,0), (1,0), (0,1), (1,1); edges 8..11 run along
//   z, at (x, y) = (0,0), (1,0), (0,1), (1,1). kEdgeCorners lists each edge's corners, lower first.
// - A corner is inside when its value is < 0; a value >= 0 (exact zero included) is outside. An
//   edge is crossed when its two corners differ in that sense, and then exactly once.
// - Triangles use vertex ids 0..11 (the vertex on that edge; the caller places it at the edge's
//   crossing, by linear interpolation or root finding) and kInteriorVertex (12), a vertex inside
//   the cell: the subcases with a contour loop of 7 or more vertices (6.2, 7.3, 10.2, 12.x, 13.x)
//   fan that loop around it, and some tunnels (6.1.2, 7.4.2...) pass through it. Recommended
//   position: the mean of the crossing points of the edges in
//   CellTriangulation::interior_vertex_edges (what uniform_grid_mesher.h does).
// - Orientation: each triangle is counter-clockwise seen from the outside (f > 0), so its
//   geometric normal points towards increasing f.
// - Watertightness: the face test depends only on the four values of the face, symmetrically, so
//   two cells sharing a face always cut it the same way.
#pragma once

#include <array>
#include <cstdint>

namespace isomesh {

inline constexpr std::uint8_t kInteriorVertex = 12;

/// kEdgeCorners[e] = {lower corner, upper corner} of edge e (see the conventions above).
inline constexpr std::array<std::array<std::uint8_t, 2>, 12> kEdgeCorners{{
    {0, 1},
    {2, 3},
    {4, 5},
    {6, 7},  // along x
    {0, 2},
    {1, 3},
    {4, 6},
    {5, 7},  // along y
    {0, 4},
    {1, 5},
    {2, 6},
    {3, 7},  // along z
}};

struct CellTriangulation {
    std::uint8_t triangle_count = 0;
    /// triangles[0 .. triangle_count): vertex ids 0..11 (edges) or kInteriorVertex.
    std::array<std::array<std::uint8_t, 3>, 12> triangles{};
    /// Bit e set for the edges of the contour loop(s) around kInteriorVertex (0 when unused): the
    /// recommended position of that vertex is the mean of these edges' crossing points.
    std::uint16_t interior_vertex_edges = 0;

    bool uses_interior_vertex() const;
};

/// Bit i set when corner i is inside (value < 0): the index of the cell's sign configuration.
std::uint8_t corner_configuration(const std::array<double, 8>& corner_values);

/// Triangulation of the isosurface (value 0) of the trilinear interpolant of the cell, with the
/// topology of that surface inside the cell. Precondition: every value is finite.
CellTriangulation triangulate_cell(const std::array<double, 8>& corner_values);

/// The face test (asymptotic decider): whether the inside corners of an ambiguous face are joined
/// across it. a, b, c, d are the face's values in cyclic order; precondition: a and c are on one
/// side of 0 and b and d on the other. Invariant under rotating and reversing the cycle, exactly,
/// so neighbouring cells agree; a tie (saddle value exactly 0) joins the outside corners.
bool face_joins_inside(double a, double b, double c, double d);

/// The decisions behind triangulate_cell, for tests and diagnostics.
struct CellDecision {
    std::uint8_t config = 0;        ///< corner_configuration
    std::uint8_t joined_faces = 0;  ///< bit f: face f (mc33_tables.h) joins its inside corners
    /// The two contour loops (indices into mc33::cell_loops(config, joined_faces)) bounding a
    /// tube through the cell, or -1, -1 when every loop bounds a disk.
    std::array<std::int8_t, 2> tube{-1, -1};
    /// Pairs of same-sign surface patches the interior test joined through the cell (1 for a
    /// tube; more would be a configuration the trilinear interpolant cannot produce).
    std::uint8_t interior_joins = 0;
};
CellDecision decide_cell(const std::array<double, 8>& corner_values);

}  // namespace isomesh
