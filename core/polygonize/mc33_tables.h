// Case tables of Marching Cubes 33 (see mc33.h for the cell conventions and the papers).
//
// Chernyaev's 33 configurations are generated here rather than typed in: for each sign
// configuration of the 8 corners (256) and each outcome of the face tests of its ambiguous faces,
// the isosurface's boundary on the cube (the contour loops drawn by the face segments) and the
// sign regions ("patches") of the cube's surface are traced by a program at first use. The
// trilinear interpolant's surface inside the cell is then a disk per loop, except that the interior
// test may find two same-sign patches joined through the cell, in which case the two loops around
// the patch between them bound a tube (the "tunnel" subcases 4.1.2, 6.1.2, 7.4.2, 10.1.2, 12.1.2,
// 13.5.2 of Chernyaev). mc33_tables_test.cpp checks every entry, and classifies the
// configurations realised by random cells under the cube's 24 rotations and complementation: they
// fall into exactly the paper's 15 cases and 33 subcases.
#pragma once

#include <array>
#include <cstdint>

namespace isomesh::mc33 {

/// Faces: 0: x = 0, 1: x = 1, 2: y = 0, 3: y = 1, 4: z = 0, 5: z = 1. Corners counter-clockwise
/// seen from inside the cell, so corners 0 and 2 (and 1 and 3) of a face are diagonal.
inline constexpr std::array<std::array<std::uint8_t, 4>, 6> kFaceCorners{{
    {0, 2, 6, 4},
    {1, 5, 7, 3},
    {0, 4, 5, 1},
    {2, 3, 7, 6},
    {0, 1, 3, 2},
    {4, 6, 7, 5},
}};

/// The edge joining two corners of the cell that differ in exactly one coordinate.
std::uint8_t edge_between(std::uint8_t corner_a, std::uint8_t corner_b);

/// Bit f set for the two faces containing edge e.
std::uint8_t edge_faces(std::uint8_t edge);

/// Which segments between two vertices on one face (chords across an ambiguous face: they lie in
/// the face) a triangulation may use. The neighbouring cell must not draw the same chord, or the
/// edge would have four triangles: disks never use chords, and tubes use them only when they must
/// (see mc33.cpp), preferring the chords of the faces the cell owns: those above it on each axis
/// (faces 1, 3 and 5); the cell across such a face draws no chord there before its last resort.
enum class Chords { kNone, kOwned, kAny };

/// Whether edge vertices a and b may be joined by a triangle edge inside the cell.
inline bool may_join(std::uint8_t edge_a, std::uint8_t edge_b, Chords chords) {
    constexpr std::uint8_t kLowerFaces = 0b010101;
    const std::uint8_t shared = edge_faces(edge_a) & edge_faces(edge_b);
    switch (chords) {
        case Chords::kNone:
            return shared == 0;
        case Chords::kOwned:
            return (shared & kLowerFaces) == 0;
        case Chords::kAny:
            return true;
    }
    return false;
}

/// Bit f set when face f is ambiguous for this configuration (bit i = corner i inside): its
/// diagonal corners have equal signs and its adjacent corners differ, so the face test decides.
std::uint8_t ambiguous_faces(std::uint8_t config);

inline constexpr int kMaxLoops = 4;

/// The contour loops of a cell on the cube's surface, with the patches they separate.
struct CellLoops {
    std::uint8_t loop_count = 0;
    /// Loop l is vertices[loop_begin[l] .. loop_begin[l + 1]) (edge ids), oriented so that the
    /// inside (negative) patch is on its left seen from inside the cell; a fan over it in this
    /// order is counter-clockwise seen from outside.
    std::array<std::uint8_t, kMaxLoops + 1> loop_begin{};
    std::array<std::uint8_t, 12> vertices{};
    /// The patch (connected region of one sign on the cube's surface) of each corner, numbered
    /// from 0 in order of first corner.
    std::array<std::uint8_t, 8> corner_patch{};
    std::uint8_t patch_count = 0;
    /// loop_patches[l] = {inside patch, outside patch} on either side of loop l.
    std::array<std::array<std::uint8_t, 2>, kMaxLoops> loop_patches{};
    /// The disk over loop l is triangles[disk_begin[l] .. disk_begin[l + 1]), oriented like the
    /// loop. Loops of 7 or more vertices, and loops that no triangulation can cover without a
    /// chord, are fanned around kInteriorVertex (at most one loop per cell); the others get the
    /// triangulation of least total diagonal length (at the edge midpoints) without chords.
    std::array<std::uint8_t, kMaxLoops + 1> disk_begin{};
    std::array<std::array<std::uint8_t, 3>, 12> triangles{};
    /// Bit e set for the edges of the loop fanned around kInteriorVertex, if any.
    std::uint16_t interior_vertex_edges = 0;

    std::uint8_t loop_size(int l) const { return loop_begin[l + 1] - loop_begin[l]; }
    const std::uint8_t* loop(int l) const { return &vertices[loop_begin[l]]; }
};

/// The loops of configuration `config` when the inside corners are joined across exactly the
/// faces in `joined_faces`. Precondition: joined_faces is a subset of ambiguous_faces(config).
/// Thread-safe (the tables are built once, at first use).
const CellLoops& cell_loops(std::uint8_t config, std::uint8_t joined_faces);

}  // namespace isomesh::mc33
