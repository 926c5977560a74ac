# The per-rank VTK pieces of `mpirun -n K tvf generate` (issue 19; docs/file_formats.md,
# "VTK series"): generates small scenes with K ranks, then reads every frame of DIR/field.pvd
# (field_NNNN.pvtu, each joining K pieces field_NNNN_pR.vtu) with VTK's own parallel reader
# and compares it with the assembled outputs rank 0 wrote (field.npy, vertices.npy,
# faces.npy, times.npy): every vertex present, its vectors equal to field.npy's (halo
# duplicates included), every face present once, the pieces' own vertices disjoint.
# Exits non-zero, listing the differences, when anything disagrees.
# Usage: python3 check_vtk_pieces.py TVF_CLI RANKS MPIRUN [MPIRUN ARGS...]
#   (the MPIRUN words without the rank count: it adds `-n RANKS`; Debian's python3-vtk9
#   and python3-numpy; exits 77, skipped, without them)
#     or: python3 check_vtk_pieces.py --folder DIR RANKS
#   checks a folder already written (the npy files beside the pieces; tests/field/vtk_io_test).
import os, subprocess, sys, tempfile
import xml.etree.ElementTree as ET
try:
    import numpy as np
    from vtkmodules.vtkIOXML import vtkXMLPUnstructuredGridReader, vtkXMLUnstructuredGridReader
    from vtkmodules.util.numpy_support import vtk_to_numpy
except ImportError as e:  # ctest reports the test skipped (SKIP_RETURN_CODE 77)
    print('skipped: numpy and VTK are needed (%s)' % e)
    sys.exit(77)

if sys.argv[1] == '--folder':
    folder, ranks = sys.argv[2], int(sys.argv[3])
else:
    folder, cli, ranks, mpirun = None, sys.argv[1], int(sys.argv[2]), sys.argv[3:]

SCENES = {
    # A planar grid with a singularity moving across the partition boundary.
    'grid': '''{"tvf": 1,
      "domain": {"grid": {"size": [31, 31], "min": [-1, -1], "max": [1, 1]}},
      "time": {"frames": 8, "range": [0, 1]},
      "generator": "spacetime",
      "elements": [{"kind": "singular", "type": "ccw_center", "path": [[-0.7, -0.6, 0], [0.7, 0.6, 1]]}],
      "keyframes": [{"t": 0, "elements": [{"kind": "singular", "type": "source", "at": [0, 0.5]}]}]}''',
    # Projected after the solve: the field is rank 0's alone then, and the other ranks'
    # shares are refreshed from it before they write their pieces.
    'projected': '''{"tvf": 1,
      "domain": {"grid": {"size": [25, 25], "min": [-1, -1], "max": [1, 1]}},
      "time": {"frames": 6, "range": [0, 1]},
      "generator": "spacetime",
      "incompressible": true,
      "elements": [{"kind": "singular", "type": "ccw_center", "path": [[-0.7, -0.6, 0], [0.7, 0.6, 1]]}],
      "keyframes": [{"t": 0, "elements": [{"kind": "singular", "type": "ccw_center", "at": [0, 0.5]}]}]}''',
    # A closed surface mesh.
    'sphere': '''{"tvf": 1,
      "domain": {"sphere": {"subdivisions": 2, "radius": 1}},
      "time": {"frames": 6, "range": [0, 1]},
      "generator": "spacetime",
      "falloff": 20,
      "elements": [{"kind": "singular", "type": "ccw_center",
                    "path": [[1, 0, 0, 0], [0, 1, 0, 0.5], [-1, 0, 0, 1]]},
                   {"kind": "singular", "type": "source", "path": [[0, 0, 1, 0]]}]}''',
    # The per-frame generator (no distributed solve: contiguous blocks of vertices).
    'constrained': '''{"tvf": 1,
      "domain": {"grid": {"size": [21, 21], "min": [-1, -1], "max": [1, 1]}},
      "time": {"frames": 5, "range": [0, 1]},
      "generator": "constrained",
      "elements": [{"kind": "singular", "type": "ccw_center", "path": [[-0.7, -0.6, 0], [0.7, 0.6, 1]]},
                   {"kind": "singular", "type": "source", "path": [[0, 0.5, 0]]}]}''',
}

errors = []
def check(ok, what):
    if not ok:
        errors.append(what)

def check_folder(name, out):
    verts = np.load(os.path.join(out, 'vertices.npy'))
    faces = np.load(os.path.join(out, 'faces.npy'))
    times = np.load(os.path.join(out, 'times.npy'))
    field = np.load(os.path.join(out, 'field.npy'))
    nv = len(verts)
    check(not any(f.startswith('field_') and f.endswith('.vtu') and '_p' not in f for f in os.listdir(out)),
          '%s: one-process frames written beside the pieces' % name)
    root = ET.parse(os.path.join(out, 'field.pvd')).getroot()
    sets = root.find('Collection').findall('DataSet')
    check(len(sets) == len(times), '%s: pvd has %d data sets for %d frames' % (name, len(sets), len(times)))
    for j, ds in enumerate(sets):
        what = '%s frame %d' % (name, j)
        check(float(ds.get('timestep')) == times[j], '%s: timestep %s vs %r' % (what, ds.get('timestep'), times[j]))
        check(ds.get('file') == 'field_%04d.pvtu' % j, '%s: file name %s' % (what, ds.get('file')))
        pvtu = os.path.join(out, ds.get('file'))
        pieces = ET.parse(pvtu).getroot().find('PUnstructuredGrid').findall('Piece')
        check([p.get('Source') for p in pieces] == ['field_%04d_p%d.vtu' % (j, r) for r in range(ranks)],
              '%s: pieces %s' % (what, [p.get('Source') for p in pieces]))
        # Every rank holds vertices of its own.
        for p in pieces:
            r = vtkXMLUnstructuredGridReader()
            r.SetFileName(os.path.join(out, p.get('Source')))
            r.Update()
            ghost = vtk_to_numpy(r.GetOutput().GetPointData().GetArray('vtkGhostType'))
            check(np.count_nonzero(ghost == 0) > 0, '%s: piece %s owns no vertex' % (what, p.get('Source')))
            tv = r.GetOutput().GetFieldData().GetArray('TimeValue')
            check(tv is not None and tv.GetValue(0) == times[j], '%s: TimeValue of %s' % (what, p.get('Source')))
        r = vtkXMLPUnstructuredGridReader()
        r.SetFileName(pvtu)
        r.Update()
        if r.GetErrorCode() != 0:
            errors.append('%s: reader error' % what)
            continue
        g = r.GetOutput()
        pd = g.GetPointData()
        check(pd.GetVectors() is not None and pd.GetVectors().GetName() == 'vector', '%s: active vectors' % what)
        vertex = vtk_to_numpy(pd.GetArray('vertex')).astype(np.int64)
        ghost = vtk_to_numpy(pd.GetArray('vtkGhostType'))
        vec = vtk_to_numpy(pd.GetArray('vector'))
        mag = vtk_to_numpy(pd.GetArray('magnitude'))
        pts = vtk_to_numpy(g.GetPoints().GetData())
        check(g.GetNumberOfPoints() >= nv and vertex.min() >= 0 and vertex.max() < nv, '%s: vertex ids' % what)
        # Every vertex once as its owner's, halo copies besides.
        check(np.array_equal(np.sort(vertex[ghost == 0]), np.arange(nv)), '%s: owned vertices are not a partition' % what)
        check(np.array_equal(np.unique(vertex), np.arange(nv)), '%s: vertices missing' % what)
        check(np.array_equal(pts, verts[vertex]), '%s: points' % what)
        # The vectors: field.npy's, halo duplicates included.
        check(vec.dtype == np.float32 and np.array_equal(vec, field[j][vertex]), '%s: vectors differ from field.npy' % what)
        check(np.allclose(mag, np.linalg.norm(field[j][vertex].astype(np.float64), axis=1), rtol=1e-6, atol=1e-6),
              '%s: magnitude' % what)
        # Every face once, corners in their order.
        conn = vtk_to_numpy(g.GetCells().GetConnectivityArray()).reshape(-1, 3)
        check(np.all(vtk_to_numpy(g.GetCellTypesArray()) == 5), '%s: cell types' % what)
        got = vertex[conn]
        check(len(got) == len(faces) and
              np.array_equal(got[np.lexsort(got.T[::-1])], faces[np.lexsort(faces.T[::-1])]),
              '%s: faces differ from faces.npy' % what)
    return len(sets)

if folder:
    frames = check_folder('folder', folder)
else:
    with tempfile.TemporaryDirectory() as tmp:
        frames = 0
        for name, text in SCENES.items():
            scene = os.path.join(tmp, name + '.json')
            with open(scene, 'w') as f:
                f.write(text)
            out = os.path.join(tmp, name)
            run = subprocess.run(mpirun + ['-n', str(ranks), cli, 'generate', scene, '-o', out, '--quiet', '--vtk-pieces'],
                                 stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
            if run.returncode != 0:
                errors.append('%s: mpirun exited %d:\n%s' % (name, run.returncode, run.stdout))
                continue
            frames += check_folder(name, out)
        # Without --vtk-pieces, K ranks write the one-process series (DESIGN.md §12: the same
        # outputs as one process), and it replaces the pieces of the run before.
        out = os.path.join(tmp, 'grid')
        run = subprocess.run(mpirun + ['-n', str(ranks), cli, 'generate', os.path.join(tmp, 'grid.json'), '-o', out,
                              '--quiet'], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        check(run.returncode == 0, 'K ranks without --vtk-pieces: exit %d:\n%s' % (run.returncode, run.stdout))
        left = sorted(f for f in os.listdir(out) if f.endswith('.pvtu') or '_p' in f)
        check(left == [], 'K ranks without --vtk-pieces left the pieces %s' % left)
        check(os.path.exists(os.path.join(out, 'field_0000.vtu')), 'K ranks without --vtk-pieces wrote no field_0000.vtu')
        run = subprocess.run(mpirun + ['-n', str(ranks), cli, 'generate', os.path.join(tmp, 'grid.json'), '-o', out,
                              '--quiet', '--vtk-pieces'], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        check(run.returncode == 0 and not os.path.exists(os.path.join(out, 'field_0000.vtu')),
              'K ranks with --vtk-pieces after a one-process series: exit %d, field_0000.vtu left' % run.returncode)
        # One process into a folder of K ranks' pieces: its field_NNNN.vtu replace them.
        out = os.path.join(tmp, 'grid')
        run = subprocess.run([cli, 'generate', os.path.join(tmp, 'grid.json'), '-o', out, '--quiet'],
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        check(run.returncode == 0, 'one process into the pieces: exit %d:\n%s' % (run.returncode, run.stdout))
        left = sorted(f for f in os.listdir(out) if f.endswith('.pvtu') or '_p' in f)
        check(left == [], 'one process left the pieces %s' % left)
        check(os.path.exists(os.path.join(out, 'field_0000.vtu')), 'one process wrote no field_0000.vtu')
if errors:
    print('\n'.join(errors))
    sys.exit(1)
print('ok', frames)
