// The real peer of bench_pipeline.cpp, built when CMake finds VTK (Debian's libvtk9-dev; optional,
// benchmarks only): f sampled natively on the (n + 1)^3 points of a uniform grid into a
// vtkImageData, then VTK's own vtkFlyingEdges3D (Schroeder, Maynard and Geveci, LDAV 2015) with
// its normals on (its default), as the "numpy sampling plus VTK flying edges" does, with
// the sampling compiled instead of interpreted.
//
// - The samples are single precision (vtkFloatArray, half the memory of doubles; f is evaluated in
//   double precision and rounded), x fastest, as VTK images are laid out.
// - VTK runs on one thread (vtkSMPTools' sequential backend, set once by vtk_flying_edges_mesh),
//   so that its thread CPU time is all its work, as the pipeline's is on one thread.
// - Copying VTK's output into a Mesh (for the rms distance and the topology) is not timed.
#pragma once

#include "grid_baseline.h"
#include "mesh/mesh.h"
#include "native_functions.h"

namespace isomesh::bench {

/// VTK's flying-edges mesh of f = 0 over the grid of `cells` cells per axis spanning `box`: what
/// grid_mesh makes, by VTK (plain Marching Cubes cases: an ambiguous face may be split the other
/// way than MC33 splits it). When `times` is given, sampling and meshing (vtkFlyingEdges3D::Update)
/// are timed apart. Precondition: cells >= 1, box valid.
Mesh vtk_flying_edges_mesh(NativeBatch f, const Box& box, int cells, GridTimes* times = nullptr);

}  // namespace isomesh::bench
