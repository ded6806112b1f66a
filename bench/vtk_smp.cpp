// VTK's SMP backend chosen apart from vtk_baseline.cpp: Debian's VTK 9.1 vtkSMPTools.h does not
// compile as C++20 (a constructor named with its template arguments), so this file alone is
// compiled as C++17 (bench/CMakeLists.txt) and includes nothing of ours.
#include <vtkSMPTools.h>

namespace isomesh::bench {

/// Makes VTK's filters run on the calling thread (declared in vtk_baseline.cpp); false if this VTK
/// has no sequential backend.
bool use_sequential_vtk_backend() {
    return vtkSMPTools::SetBackend("Sequential");
}

}  // namespace isomesh::bench
