// The functions of bench_pipeline's gallery compiled natively: the uniform-grid baseline
// (grid_baseline.h) samples them, as a person meshing these surfaces with a grid would write them
// in C++. The expressions are written by hand in native_functions.cpp; the .vm models are
// translated to straight-line C++ at build time (vm_to_cpp.cmake). All are compiled with the
// evaluator's flags (-O3 -fno-math-errno -fno-trapping-math) and AVX2 clones
// (ISOMESH_VECTOR_CLONES), so GCC vectorizes them as it vectorizes the evaluator's loops.
#pragma once

#include <cstddef>

namespace isomesh::bench {

/// out[i] = f(x[i], y[i], z[i]) for i < n.
using NativeBatch = void (*)(const double* x, const double* y, const double* z, double* out,
                             std::size_t n);

void native_torus(const double* x, const double* y, const double* z, double* out, std::size_t n);
void native_tanglecube(const double* x, const double* y, const double* z, double* out,
                       std::size_t n);
void native_gyroid(const double* x, const double* y, const double* z, double* out, std::size_t n);
void native_heart(const double* x, const double* y, const double* z, double* out, std::size_t n);
void native_genus_two(const double* x, const double* y, const double* z, double* out,
                      std::size_t n);
void native_spheroid(const double* x, const double* y, const double* z, double* out, std::size_t n);
void native_cosine_sphere(const double* x, const double* y, const double* z, double* out,
                          std::size_t n);
void native_thesis_sphere(const double* x, const double* y, const double* z, double* out,
                          std::size_t n);
void native_blobby_cube(const double* x, const double* y, const double* z, double* out,
                        std::size_t n);

}  // namespace isomesh::bench

// Generated from the .vm files at build time (bench/CMakeLists.txt).
void native_bear(const double* x, const double* y, const double* z, double* out, std::size_t n);
void native_colonnade(const double* x, const double* y, const double* z, double* out,
                      std::size_t n);
