// The compiled uniform-grid baseline that bench_pipeline.cpp measures the pipeline against: what a
// person meshing a formula without isomesh would do with the best-known tools, sample f on a
// uniform grid with compiled code and run a flying-edges style Marching Cubes over it.
//
// - Sampling: f compiled natively (native_functions.h), evaluated one z plane at a time over the
//   plane's (n + 1)^2 points in one batch call (a loop the compiler vectorizes: AVX2 clones, the
//   evaluator's flags); only four planes are kept (the two of the current slab of cells and one
//   each side, for the normals' central differences), so memory stays O(n^2) and in cache.
// - Meshing, as flying edges does it (Schroeder, Maynard and Geveci, "Flying edges: a
//   high-performance scalable isocontouring algorithm", IEEE LDAV 2015): per grid row, the span
//   between its first and last sign change along x ("trimming": a row of cells is visited only
//   between the first and last crossing of its four rows, and skipped outright when the four rows
//   have no crossing and one sign); one vertex per crossed grid edge, by linear interpolation,
//   made once in an edge pass and shared by the four cells around the edge through per-plane
//   edge index arrays; normals from central differences of the samples, interpolated along the
//   edge (as vtkFlyingEdges3D's ComputeNormals, on by default).
// - Cells: Marching Cubes 33 (polygonize/mc33.h, the project's tables), so the mesh has the
//   topology of the grid's trilinear interpolant and is watertight. A configuration whose
//   triangulation does not depend on the values (no ambiguous face, one contour loop: nearly every
//   crossed cell of a smooth surface) is a table lookup like classic Marching Cubes; only the
//   ambiguous ones run the face and interior tests.
// - One thread (the pipeline is measured on one thread too).
//
// Throughput (bench_pipeline prints it on every run, "Peers' throughput", beside VTK's
// vtkFlyingEdges3D on the same samples: vtk_baseline.h): in one run with a load average of about
// 5 on 2 cores, thread CPU time, the meshing pass ran at 200-780 million cells per second on the
// smooth surfaces (trimming skips most cells), 1.2-3 times VTK's; for functions with sines or
// exponentials (the gyroid, the models) the time is mostly sampling. (Flying edges' paper finds
// the serial algorithm several times faster than VTK's Marching Cubes and Synchronized Templates
// on volumes already in memory.) For the comparison (numpy sampling plus vtkFlyingEdges3D
// on a 129^3 grid: 0.34 s for bear.vm, 0.24 s for colonnade.vm), bench_pipeline prints both peers'
// times at 129^3.
#pragma once

#include "eval/evaluator.h"
#include "mesh/mesh.h"
#include "native_functions.h"

namespace isomesh::bench {

struct GridTimes {
    double sampling = 0.0;  ///< thread CPU seconds evaluating f
    double meshing = 0.0;   ///< thread CPU seconds for everything else
};

/// The mesh of f = 0 over the grid of `cells` cells per axis spanning `box` ((cells + 1)^3
/// samples, corners included): vertices on the grid edges by linear interpolation, unit normals
/// from the samples' central differences, triangles counter-clockwise seen from f > 0 (as the
/// pipeline's). Cells with a non-finite sample are skipped. No adjacency (neighbours, base edges).
/// When `times` is given, sampling and meshing are timed apart (a clock read per plane).
/// Precondition: cells >= 1, box valid.
Mesh grid_mesh(NativeBatch f, const Box& box, int cells, GridTimes* times = nullptr);

}  // namespace isomesh::bench
