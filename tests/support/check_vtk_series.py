# Reads a VTK series written by tvf (DIR/field.pvd + field_NNNN.vtu) with VTK's own
# XML reader and compares it with the NumPy arrays in REF (vertices, faces, times,
# field .npy). Exits non-zero, listing the differences, when anything disagrees.
# Usage: python3 check_vtk_series.py DIR REF   (Debian's python3-vtk9 and python3-numpy)
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
