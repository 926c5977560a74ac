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

TEST(VtkSeries, FilesAndCollection) {
  const Mesh& mesh = test::grid_mesh();
  const TangentBundle bundle(mesh);
  const Field field = moving_field(mesh, TimeSampling{0.0, 1.0, 3});
  TempDir dir;
  write_vtk_series(dir.path().string(), "f", bundle, field);
  EXPECT_EQ(test::listing(dir.path()),
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

  const auto r = test::run_command("'" + py + "' '" + test::source_dir() + "/tests/support/check_vtk_series.py' '" +
                                   dir.path().string() + "' '" + (dir / "ref").string() + "'");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, "ok " + std::to_string(n) + "\n");
}

TEST(VtkSeries, VtkReadsTheGridSeries) { check_with_vtk(test::grid_mesh(), TimeSampling{-0.3, 0.9, 4}); }

TEST(VtkSeries, VtkReadsTheIcosphereSeries) {
  check_with_vtk(test::icosphere_mesh(), TimeSampling{0.0, 1.0, 3});
}

// The distributed form (mpirun -n K): the pieces of K ranks, as each rank writes its own,
// then the .pvtu files and the .pvd; VTK's parallel reader joins them into every vertex
// (halo duplicates agreeing) and every face once (tests/support/check_vtk_pieces.py,
// which ctest's mpi_vtk_pieces also runs on `mpirun -n 2 tvf generate`).
void check_pieces_with_vtk(const Mesh& mesh, const TimeSampling& ts, int ranks) {
  const std::string py = test::python();
  if (py.empty() ||
      test::run_command("'" + py + "' -c 'import numpy, vtkmodules.vtkIOXML'").exit_code != 0)
    GTEST_SKIP() << "Debian python3 with numpy and vtk not available";
  const TangentBundle bundle(mesh);
  const Field field = moving_field(mesh, ts);
  // Stripes across x: owners not contiguous in the vertex order, every rank with a share.
  double lo = mesh.position(0).x(), hi = lo;
  for (const Vec3& p : mesh.positions()) lo = std::min(lo, p.x()), hi = std::max(hi, p.x());
  std::vector<int> owner;
  for (const Vec3& p : mesh.positions())
    owner.push_back(std::min(ranks - 1, static_cast<int>(ranks * (p.x() - lo) / (hi - lo))));
  TempDir dir;
  for (int r = 0; r < ranks; ++r) write_vtk_series_piece(dir.path().string(), "field", bundle, field, owner, r);
  write_vtk_parallel_series(dir.path().string(), "field", ts.times(), ranks);
  EXPECT_TRUE(fs::exists(dir / "field_0000.pvtu"));
  EXPECT_TRUE(fs::exists(dir / ("field_0000_p" + std::to_string(ranks - 1) + ".vtu")));
  EXPECT_FALSE(fs::exists(dir / "field_0000.vtu"));
  const auto nv = static_cast<size_t>(mesh.num_vertices());
  const auto nf = static_cast<size_t>(mesh.num_faces());
  const auto n = static_cast<size_t>(field.frames());
  std::vector<double> verts;
  for (const Vec3& p : mesh.positions()) verts.insert(verts.end(), {p.x(), p.y(), p.z()});
  std::vector<std::int32_t> faces;
  for (const Face& f : mesh.faces()) faces.insert(faces.end(), f.begin(), f.end());
  const std::vector<double> times = ts.times();
  const std::vector<float> world = world_vectors_f32(bundle, field);
  write_npy((dir / "vertices.npy").string(), {nv, 3}, verts.data());
  write_npy((dir / "faces.npy").string(), {nf, 3}, faces.data());
  write_npy((dir / "times.npy").string(), {n}, times.data());
  write_npy((dir / "field.npy").string(), {n, nv, 3}, world.data());

  const auto r = test::run_command("'" + py + "' '" + test::source_dir() +
                                   "/tests/support/check_vtk_pieces.py' --folder '" + dir.path().string() + "' " +
                                   std::to_string(ranks));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, "ok " + std::to_string(n) + "\n");
}

TEST(VtkSeries, VtkJoinsTheGridPiecesOfThreeRanks) {
  check_pieces_with_vtk(test::grid_mesh(), TimeSampling{-0.3, 0.9, 4}, 3);
}

TEST(VtkSeries, VtkJoinsTheIcospherePiecesOfTwoRanks) {
  check_pieces_with_vtk(test::icosphere_mesh(), TimeSampling{0.0, 1.0, 3}, 2);
}

TEST(VtkSeries, VtkReadsScalarSeries) {
  // Two per-vertex arrays (FTLE-like, one with a NaN) read back by VTK's reader: the
  // values of the last time and the time of each file.
  const std::string py = test::python();
  if (py.empty() ||
      test::run_command("'" + py + "' -c 'import numpy, vtkmodules.vtkIOXML'").exit_code != 0)
    GTEST_SKIP() << "Debian python3 with numpy and vtk not available";
  const Mesh& mesh = test::grid_mesh();
  const auto nv = static_cast<size_t>(mesh.num_vertices());
  const std::vector<double> times{0.5, 1.5};
  std::vector<float> a(2 * nv), b(2 * nv);
  for (size_t k = 0; k < a.size(); ++k) {
    a[k] = static_cast<float>(k);
    b[k] = -static_cast<float>(k) / 4;
  }
  b[nv + 3] = std::nanf("");
  TempDir dir;
  write_vtk_scalar_series(dir.path().string(), "ftle", mesh, times, {{"ftle_forward", a}, {"ftle_backward", b}});
  EXPECT_EQ(test::listing(dir.path()), (std::vector<std::string>{"ftle.pvd", "ftle_0000.vtu", "ftle_0001.vtu"}));
  const std::string script =
      "import numpy as np\n"
      "from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader\n"
      "from vtkmodules.util.numpy_support import vtk_to_numpy\n"
      "r = vtkXMLUnstructuredGridReader(); r.SetFileName('" + (dir / "ftle_0001.vtu").string() + "'); r.Update()\n"
      "g = r.GetOutput(); pd = g.GetPointData()\n"
      "f = vtk_to_numpy(pd.GetArray('ftle_forward')); b = vtk_to_numpy(pd.GetArray('ftle_backward'))\n"
      "t = vtk_to_numpy(g.GetFieldData().GetArray('TimeValue'))[0]\n"
      "n = g.GetNumberOfPoints()\n"
      "ok = (f == np.arange(n, 2 * n)).all() and np.isnan(b[3]) and b[4] == -(n + 4) / 4 and t == 1.5\n"
      "print('ok' if ok else 'bad %s %s %s' % (f[:3], b[:5], t))\n";
  test::write_text(dir / "check.py", script);
  const auto r = test::run_command("'" + py + "' '" + (dir / "check.py").string() + "'");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, "ok\n");
}

}  // namespace
}  // namespace tvf
