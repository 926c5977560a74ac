#include "tvf/field/vtk_io.h"

#include "tvf/field/npy.h"
#include "tvf/field/world_vectors.h"
#include "support/test_meshes.h"
#include "support/test_paths.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace tvf {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

// A smooth field that changes with time: frame j rotates and scales a vertex-dependent
// vector.
Field moving_field(const Mesh& mesh, const TimeSampling& ts) {
  Field field(ts, mesh.num_vertices());
  for (int j = 0; j < ts.frames; ++j)
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      const Vec3& p = mesh.position(v);
      field.at(j, v) = std::polar(1.0 + 0.5 * p.x() + 0.1 * j, 0.7 * j + p.y() - 2 * p.z());
    }
  return field;
}

std::vector<std::string> listing(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

TEST(VtkSeries, FilesAndCollection) {
  const Mesh& mesh = test::grid_mesh();
  const TangentBundle bundle(mesh);
  const Field field = moving_field(mesh, TimeSampling{0.0, 1.0, 3});
  TempDir dir;
  write_vtk_series(dir.path().string(), "f", bundle, field);
  EXPECT_EQ(listing(dir.path()),
            (std::vector<std::string>{"f.pvd", "f_0000.vtu", "f_0001.vtu", "f_0002.vtu"}));
  const std::string pvd = test::read_text(dir / "f.pvd");
  EXPECT_NE(pvd.find("<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\">"),
            std::string::npos);
  EXPECT_NE(pvd.find("<DataSet timestep=\"0\" part=\"0\" file=\"f_0000.vtu\"/>"), std::string::npos);
  EXPECT_NE(pvd.find("<DataSet timestep=\"0.5\" part=\"0\" file=\"f_0001.vtu\"/>"), std::string::npos);
  EXPECT_NE(pvd.find("<DataSet timestep=\"1\" part=\"0\" file=\"f_0002.vtu\"/>"), std::string::npos);
  const std::string vtu = test::read_text(dir / "f_0001.vtu");
  EXPECT_EQ(vtu.rfind("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
                      "byte_order=\"LittleEndian\" header_type=\"UInt64\">",
                      0),
            0u);
  EXPECT_NE(vtu.find("<AppendedData encoding=\"raw\">"), std::string::npos);
  EXPECT_EQ(vtu.substr(vtu.size() - 11), "</VTKFile>\n");
}

// VTK's own reader gives back the mesh, the times and the world vectors: compared with
// .npy files written here (numpy loads them; npy_test checks that it does so exactly).
void check_with_vtk(const Mesh& mesh, const TimeSampling& ts) {
  const std::string py = test::python();
  if (py.empty() ||
      test::run_command("'" + py + "' -c 'import numpy, vtkmodules.vtkIOXML'").exit_code != 0)
    GTEST_SKIP() << "Debian python3 with numpy and vtk not available";
  const TangentBundle bundle(mesh);
  const Field field = moving_field(mesh, ts);
  TempDir dir;
  write_vtk_series(dir.path().string(), "field", bundle, field);
  const auto nv = static_cast<size_t>(mesh.num_vertices());
  const auto nf = static_cast<size_t>(mesh.num_faces());
  const auto n = static_cast<size_t>(field.frames());
  std::vector<double> verts;
  for (const Vec3& p : mesh.positions()) verts.insert(verts.end(), {p.x(), p.y(), p.z()});
  std::vector<std::int32_t> faces;
  for (const Face& f : mesh.faces()) faces.insert(faces.end(), f.begin(), f.end());
  const std::vector<double> times = ts.times();
  const std::vector<float> world = world_vectors_f32(bundle, field);
  fs::create_directory(dir / "ref");
  write_npy((dir / "ref" / "vertices.npy").string(), {nv, 3}, verts.data());
  write_npy((dir / "ref" / "faces.npy").string(), {nf, 3}, faces.data());
  write_npy((dir / "ref" / "times.npy").string(), {n}, times.data());
  write_npy((dir / "ref" / "field.npy").string(), {n, nv, 3}, world.data());

  test::write_text(dir / "ref" / "check.py", R"(
import os, sys
import xml.etree.ElementTree as ET
import numpy as np
from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader
from vtkmodules.util.numpy_support import vtk_to_numpy

out, ref = sys.argv[1], sys.argv[2]
verts = np.load(os.path.join(ref, 'vertices.npy'))
faces = np.load(os.path.join(ref, 'faces.npy'))
times = np.load(os.path.join(ref, 'times.npy'))
field = np.load(os.path.join(ref, 'field.npy'))
errors = []
def check(ok, what):
    if not ok:
        errors.append(what)

root = ET.parse(os.path.join(out, 'field.pvd')).getroot()
check(root.get('type') == 'Collection', 'pvd type')
sets = root.find('Collection').findall('DataSet')
check(len(sets) == len(times), 'pvd has %d data sets for %d frames' % (len(sets), len(times)))
for j, ds in enumerate(sets):
    check(float(ds.get('timestep')) == times[j], 'timestep %d: %s vs %r' % (j, ds.get('timestep'), times[j]))
    check(ds.get('file') == 'field_%04d.vtu' % j, 'file name %s' % ds.get('file'))
    r = vtkXMLUnstructuredGridReader()
    r.SetFileName(os.path.join(out, ds.get('file')))
    r.Update()
    if r.GetErrorCode() != 0:
        errors.append('reader error on ' + ds.get('file'))
        continue
    g = r.GetOutput()
    check(g.GetNumberOfPoints() == len(verts), 'points count')
    check(g.GetNumberOfCells() == len(faces), 'cells count')
    pts = vtk_to_numpy(g.GetPoints().GetData())
    check(pts.dtype == np.float64 and np.array_equal(pts, verts), 'points of frame %d' % j)
    conn = vtk_to_numpy(g.GetCells().GetConnectivityArray()).reshape(-1, 3)
    check(np.array_equal(conn, faces), 'connectivity of frame %d' % j)
    offs = vtk_to_numpy(g.GetCells().GetOffsetsArray())
    check(np.array_equal(offs, 3 * np.arange(len(faces) + 1)), 'offsets of frame %d' % j)
    check(np.all(vtk_to_numpy(g.GetCellTypesArray()) == 5), 'cell types of frame %d' % j)
    pd = g.GetPointData()
    check(pd.GetVectors() is not None and pd.GetVectors().GetName() == 'vector', 'active vectors')
    vec = vtk_to_numpy(pd.GetArray('vector'))
    check(vec.dtype == np.float32 and vec.shape == field[j].shape and np.array_equal(vec, field[j]),
          'vectors of frame %d' % j)
    mag = vtk_to_numpy(pd.GetArray('magnitude'))
    check(mag.dtype == np.float32 and mag.shape == (len(verts),), 'magnitude shape of frame %d' % j)
    ref_mag = np.linalg.norm(field[j].astype(np.float64), axis=1)
    check(np.allclose(mag, ref_mag, rtol=1e-6, atol=1e-6), 'magnitude of frame %d' % j)
    tv = g.GetFieldData().GetArray('TimeValue')
    check(tv is not None and tv.GetValue(0) == times[j], 'TimeValue of frame %d' % j)
if errors:
    print('\n'.join(errors))
    sys.exit(1)
print('ok', len(sets))
)");
  const auto r = test::run_command("'" + py + "' '" + (dir / "ref" / "check.py").string() + "' '" +
                                   dir.path().string() + "' '" + (dir / "ref").string() + "'");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, "ok " + std::to_string(n) + "\n");
}

TEST(VtkSeries, VtkReadsTheGridSeries) { check_with_vtk(test::grid_mesh(), TimeSampling{-0.3, 0.9, 4}); }

TEST(VtkSeries, VtkReadsTheIcosphereSeries) {
  check_with_vtk(test::icosphere_mesh(), TimeSampling{0.0, 1.0, 3});
}

}  // namespace
}  // namespace tvf
