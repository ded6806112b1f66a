// The gallery's expressions as C++ (see native_functions.h). Each is f = left side - right side
// of the equation bench_pipeline.cpp meshes, checked against the tape evaluator at every run.
#include "native_functions.h"

#include <cmath>

#include "eval/batch_kernels.h"  // ISOMESH_VECTOR_CLONES, as the evaluator's loops

namespace isomesh::bench {

// (sqrt(x^2+y^2)-2)^2+z^2=0.49
ISOMESH_VECTOR_CLONES void native_torus(const double* x, const double* y, const double* z,
                                        double* out, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
        const double r = std::sqrt(x[i] * x[i] + y[i] * y[i]) - 2.0;
        out[i] = r * r + z[i] * z[i] - 0.49;
    }
}

// x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8=0
ISOMESH_VECTOR_CLONES void native_tanglecube(const double* x, const double* y, const double* z,
                                             double* out, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
        const double x2 = x[i] * x[i], y2 = y[i] * y[i], z2 = z[i] * z[i];
        out[i] = x2 * x2 - 5.0 * x2 + y2 * y2 - 5.0 * y2 + z2 * z2 - 5.0 * z2 + 11.8;
    }
}

// sin(x)cos(y)+sin(y)cos(z)+sin(z)cos(x)=0
ISOMESH_VECTOR_CLONES void native_gyroid(const double* x, const double* y, const double* z,
                                         double* out, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
        out[i] = std::sin(x[i]) * std::cos(y[i]) + std::sin(y[i]) * std::cos(z[i]) +
                 std::sin(z[i]) * std::cos(x[i]);
    }
}

// (x^2+2.25y^2+z^2-1)^3-x^2z^3-0.1125y^2z^3=0
ISOMESH_VECTOR_CLONES void native_heart(const double* x, const double* y, const double* z,
                                        double* out, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
        const double x2 = x[i] * x[i], y2 = y[i] * y[i], z2 = z[i] * z[i];
        const double a = x2 + 2.25 * y2 + z2 - 1.0;
        const double z3 = z2 * z[i];
        out[i] = a * a * a - x2 * z3 - 0.1125 * y2 * z3;
    }
}

// ((x^2+y^2)^2-x^2+y^2)^2+z^2=0.01
ISOMESH_VECTOR_CLONES void native_genus_two(const double* x, const double* y, const double* z,
                                            double* out, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
        const double x2 = x[i] * x[i], y2 = y[i] * y[i];
        const double r2 = x2 + y2;
        const double a = r2 * r2 - x2 + y2;
        out[i] = a * a + z[i] * z[i] - 0.01;
    }
}

// 10x^2+y^2+z^2=20
ISOMESH_VECTOR_CLONES void native_spheroid(const double* x, const double* y, const double* z,
                                           double* out, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i)
        out[i] = 10.0 * x[i] * x[i] + y[i] * y[i] + z[i] * z[i] - 20.0;
}

// x^2+y^2+z^2+2cos(2x)=10
ISOMESH_VECTOR_CLONES void native_cosine_sphere(const double* x, const double* y, const double* z,
                                                double* out, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i)
        out[i] = x[i] * x[i] + y[i] * y[i] + z[i] * z[i] + 2.0 * std::cos(2.0 * x[i]) - 10.0;
}

// sqrt(x^2+y^2+z^2)=4.65
ISOMESH_VECTOR_CLONES void native_thesis_sphere(const double* x, const double* y, const double* z,
                                                double* out, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i)
        out[i] = std::sqrt(x[i] * x[i] + y[i] * y[i] + z[i] * z[i]) - 4.65;
}

// sqrt(x^2+y^2+z^2)+2cos(2x)+2cos(2y)+2cos(2z)=20
ISOMESH_VECTOR_CLONES void native_blobby_cube(const double* x, const double* y, const double* z,
                                              double* out, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
        out[i] = std::sqrt(x[i] * x[i] + y[i] * y[i] + z[i] * z[i]) + 2.0 * std::cos(2.0 * x[i]) +
                 2.0 * std::cos(2.0 * y[i]) + 2.0 * std::cos(2.0 * z[i]) - 20.0;
    }
}

}  // namespace isomesh::bench
