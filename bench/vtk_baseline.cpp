// VTK's flying edges as bench_pipeline's peer (see vtk_baseline.h).
#include "vtk_baseline.h"

#include <cstdint>
#include <ctime>
#include <stdexcept>
#include <vector>

#include <vtkCellArray.h>
#include <vtkCellArrayIterator.h>
#include <vtkDataArray.h>
#include <vtkFloatArray.h>
#include <vtkFlyingEdges3D.h>
#include <vtkImageData.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include "bench_clock.h"

namespace isomesh::bench {

bool use_sequential_vtk_backend();  // vtk_smp.cpp

namespace {

double process_cpu_seconds() {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

/// f on the grid's points into a VTK image, one row at a time.
vtkSmartPointer<vtkImageData> sample(NativeBatch f, const Box& box, int cells) {
    const int points = cells + 1;
    const glm::dvec3 step = box.size() / double(cells);
    auto image = vtkSmartPointer<vtkImageData>::New();
    image->SetDimensions(points, points, points);
    image->SetOrigin(box.lo.x, box.lo.y, box.lo.z);
    image->SetSpacing(step.x, step.y, step.z);
    auto values = vtkSmartPointer<vtkFloatArray>::New();
    values->SetNumberOfTuples(vtkIdType(points) * points * points);
    float* out = values->GetPointer(0);
    std::vector<double> xs(points), ys(points), zs(points), row(points);
    for (int i = 0; i < points; ++i) xs[i] = box.lo.x + step.x * i;
    for (int k = 0; k < points; ++k) {
        std::fill(zs.begin(), zs.end(), box.lo.z + step.z * k);
        for (int j = 0; j < points; ++j) {
            std::fill(ys.begin(), ys.end(), box.lo.y + step.y * j);
            f(xs.data(), ys.data(), zs.data(), row.data(), std::size_t(points));
            for (int i = 0; i < points; ++i) *out++ = static_cast<float>(row[i]);
        }
    }
    image->GetPointData()->SetScalars(values);
    return image;
}

Mesh to_mesh(vtkPolyData& polys) {
    Mesh mesh;
    vtkPoints* points = polys.GetPoints();
    vtkDataArray* normals = polys.GetPointData()->GetNormals();
    const vtkIdType n = points ? points->GetNumberOfPoints() : 0;
    mesh.positions.resize(std::size_t(n));
    for (vtkIdType p = 0; p < n; ++p) points->GetPoint(p, &mesh.positions[p].x);
    if (normals) {
        mesh.normals.resize(std::size_t(n));
        for (vtkIdType p = 0; p < n; ++p) normals->GetTuple(p, &mesh.normals[p].x);
    }
    vtkCellArray* cells = polys.GetPolys();
    mesh.triangles.reserve(std::size_t(cells->GetNumberOfCells()));
    const auto iterator = vtk::TakeSmartPointer(cells->NewIterator());
    for (iterator->GoToFirstCell(); !iterator->IsDoneWithTraversal(); iterator->GoToNextCell()) {
        vtkIdType size = 0;
        const vtkIdType* ids = nullptr;
        iterator->GetCurrentCell(size, ids);
        if (size != 3)
            throw std::logic_error("vtkFlyingEdges3D made a polygon that is no triangle");
        mesh.triangles.push_back(
            {std::uint32_t(ids[0]), std::uint32_t(ids[1]), std::uint32_t(ids[2])});
    }
    return mesh;
}

}  // namespace

Mesh vtk_flying_edges_mesh(NativeBatch f, const Box& box, int cells, GridTimes* times) {
    static const bool sequential = use_sequential_vtk_backend();
    if (!sequential) throw std::runtime_error("VTK has no sequential SMP backend");
    const double start = cpu_seconds(), process_start = process_cpu_seconds();
    const vtkSmartPointer<vtkImageData> image = sample(f, box, cells);
    const double sampled = cpu_seconds();
    auto flying_edges = vtkSmartPointer<vtkFlyingEdges3D>::New();
    flying_edges->SetInputData(image);
    flying_edges->SetValue(0, 0.0);
    flying_edges->ComputeNormalsOn();
    flying_edges->ComputeGradientsOff();
    flying_edges->ComputeScalarsOff();
    flying_edges->Update();
    // Thread CPU time is all the work only if no other thread did some.
    const double elapsed = cpu_seconds() - start;
    if (process_cpu_seconds() - process_start > 1.25 * elapsed + 1e-3)
        throw std::runtime_error("VTK ran on other threads: its thread CPU time is not its work");
    if (times) {
        times->sampling += sampled - start;
        times->meshing += cpu_seconds() - sampled;
    }
    return to_mesh(*flying_edges->GetOutput());
}

}  // namespace isomesh::bench
