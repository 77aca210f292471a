// VTK polydata files through VTK's own readers (legacy .vtk, XML .vtp). The only translation
// unit of scanmesh that includes VTK headers.
#include <vtkCellArray.h>
#include <vtkDataArray.h>
#include <vtkNew.h>
#include <vtkObject.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataReader.h>
#include <vtkSmartPointer.h>
#include <vtkTriangleFilter.h>
#include <vtkUnsignedCharArray.h>
#include <vtkXMLPolyDataReader.h>

#include <cmath>
#include <system_error>

#include "scanmesh/acquisition/scan_import.h"
#include "scanmesh/core/errors.h"

namespace scanmesh {

namespace {

vtkSmartPointer<vtkPolyData> read_polydata(const std::filesystem::path& path) {
  const std::string ext = path.extension().string();
  if (ext == ".vtp") {
    vtkNew<vtkXMLPolyDataReader> reader;
    reader->SetFileName(path.string().c_str());
    if (!reader->CanReadFile(path.string().c_str()))
      throw FileFormatError(path, "not a VTK XML polydata file");
    reader->Update();
    if (reader->GetErrorCode() != 0)
      throw FileFormatError(path, "VTK's XML reader could not read it");
    return reader->GetOutput();
  }
  vtkNew<vtkPolyDataReader> reader;
  reader->SetFileName(path.string().c_str());
  if (!reader->OpenVTKFile() || !reader->ReadHeader())
    throw FileFormatError(path, "not a VTK legacy file (no '# vtk DataFile' header)");
  reader->CloseVTKFile();
  if (!reader->IsFilePolyData())
    throw FileFormatError(path, "the VTK file holds no POLYDATA dataset");
  reader->Update();
  if (reader->GetErrorCode() != 0) throw FileFormatError(path, "VTK's reader could not read it");
  return reader->GetOutput();
}

// Point colours: the active scalars (or an array named RGB / Colors) of 3 or 4 unsigned chars.
vtkUnsignedCharArray* point_colors(vtkPolyData* data) {
  vtkPointData* pd = data->GetPointData();
  for (vtkDataArray* a : {pd->GetScalars(), pd->GetArray("RGB"), pd->GetArray("Colors")}) {
    auto* c = vtkUnsignedCharArray::SafeDownCast(a);
    if (c && (c->GetNumberOfComponents() == 3 || c->GetNumberOfComponents() == 4)) return c;
  }
  return nullptr;
}

}  // namespace

Mesh read_vtk_polydata(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw IoError("cannot read " + path.string() + ": no such file");
  // VTK reports problems in a window of its own (stderr here); the errors below say it instead.
  vtkObject::GlobalWarningDisplayOff();
  vtkSmartPointer<vtkPolyData> data = read_polydata(path);
  if (!data || data->GetNumberOfPoints() == 0) throw FileFormatError(path, "no points");
  Mesh mesh;
  const vtkIdType n = data->GetNumberOfPoints();
  mesh.positions.reserve(static_cast<std::size_t>(n));
  for (vtkIdType k = 0; k < n; ++k) {
    double p[3];
    data->GetPoint(k, p);
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
      throw FileFormatError(path, "point " + std::to_string(k) + " is not finite");
    mesh.positions.emplace_back(p[0], p[1], p[2]);
  }
  if (vtkUnsignedCharArray* c = point_colors(data); c && c->GetNumberOfTuples() == n)
    for (vtkIdType k = 0; k < n; ++k)
      mesh.colors.push_back({c->GetTypedComponent(k, 0), c->GetTypedComponent(k, 1),
                             c->GetTypedComponent(k, 2)});
  if (data->GetNumberOfPolys() + data->GetNumberOfStrips() == 0) return mesh;  // a cloud
  vtkNew<vtkTriangleFilter> triangles;
  triangles->SetInputData(data);
  triangles->PassVertsOff();
  triangles->PassLinesOff();
  triangles->Update();
  vtkPolyData* tri = triangles->GetOutput();
  vtkCellArray* polys = tri->GetPolys();
  vtkIdType npts = 0;
  const vtkIdType* ids = nullptr;
  for (polys->InitTraversal(); polys->GetNextCell(npts, ids);) {
    if (npts != 3) continue;
    for (int k = 0; k < 3; ++k)
      if (ids[k] < 0 || ids[k] >= n) throw FileFormatError(path, "a cell names a missing point");
    mesh.triangles.push_back(
        {static_cast<int>(ids[0]), static_cast<int>(ids[1]), static_cast<int>(ids[2])});
  }
  return mesh;
}

}  // namespace scanmesh
