"""A domain made in numpy: an icosphere and a planar grid as vertex and face arrays,
handed to tvf.generate and tvf.Design instead of a mesh file (potpourri3d, trimesh or
your own code give such arrays).

    PYTHONPATH=build/release/python python3 examples/python/mesh_from_numpy.py
"""
import numpy as np

import tvf


def icosphere(subdivisions):
    """The icosahedron, each triangle split in four `subdivisions` times, on the unit sphere."""
    p = (1 + 5 ** 0.5) / 2
    v = [(-1, p, 0), (1, p, 0), (-1, -p, 0), (1, -p, 0), (0, -1, p), (0, 1, p), (0, -1, -p), (0, 1, -p),
         (p, 0, -1), (p, 0, 1), (-p, 0, -1), (-p, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
         (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11),
         (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    verts = [np.array(x, float) / np.linalg.norm(x) for x in v]
    for _ in range(subdivisions):
        mids, faces = {}, []

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in mids:
                m = verts[a] + verts[b]
                verts.append(m / np.linalg.norm(m))
                mids[key] = len(verts) - 1
            return mids[key]

        for a, b, c in f:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            faces += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = faces
    return np.array(verts), np.array(f)


# A vortex circling the equator of a numpy icosphere (the scene needs no "domain").
V, F = icosphere(3)
scene = {
    "tvf": 1,
    "time": {"frames": 20, "range": [0, 1]},
    "generator": "basis",
    "falloff": 8,
    "elements": [
        {"kind": "singular", "type": "ccw_center", "path": [[1, 0, 0, 0], [0, 1, 0, 0.5], [-1, 0, 0, 1]]},
        {"kind": "singular", "type": "source", "path": [[0, 0, 1, 0]]},
    ],
}
f = tvf.generate(scene, vertices=V, faces=F)
print(f, "on", V.shape, F.shape, "arrays")
first = [s for s in tvf.analyze(f)["singularities"] if s["frame"] == 0]
for s in first:
    print(f"  t = 0: {s['type']:>12} at {np.round(s['position'], 2)}")

# A planar grid of triangles at z = 0 is a planar domain.
n = 33
x = np.linspace(-1, 1, n)
xx, yy = np.meshgrid(x, x)
Vg = np.stack([xx.ravel(), yy.ravel(), np.zeros(n * n)], axis=1)
idx = np.arange(n * n).reshape(n, n)
a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel(), idx[1:, :-1].ravel()
Fg = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
# Points on a mesh domain are [x, y, z, t], on a planar one too.
design = tvf.Design({"tvf": 1, "time": {"frames": 10}, "generator": "basis",
                     "elements": [{"kind": "singular", "type": "saddle", "path": [[0, 0, 0, 0]]}]},
                    vertices=Vg, faces=Fg)
g = design.generate()
print(g, "planar:", g.planar, "| scene domain:", design.scene["domain"])

# A broken mesh is refused with the sentence a mesh file gets.
try:
    tvf.generate(scene, vertices=V, faces=np.vstack([F, [[0, 1, len(V)]]]))
except ValueError as e:
    print("refused:", e)
