#!/usr/bin/env python3
"""Writes the double gyre of Shadden, Lekien & Marsden (2005) as a tvf field file.

    u = -pi A sin(pi f) cos(pi y),  v = pi A cos(pi f) sin(pi y) df/dx,
    f(x, t) = a(t) x^2 + b(t) x,  a = eps sin(w t),  b = 1 - 2 eps sin(w t),
    A = 0.1, eps = 0.25, w = 2 pi / 10, on [0, 2] x [0, 1].

No generator of tvf makes this field (it is given in closed form, not designed), so the
example writes it directly in the native field format (docs/file_formats.md): a grid in
tvf's vertex order and triangulation (index = iy*nx + ix; each cell split along its
(ix, iy)-(ix+1, iy+1) diagonal), and the vectors in each vertex's tangent basis, which on
a planar grid is world x, y. Usage:

    python3 make_double_gyre.py OUT_DIR [--nx 101] [--ny 51] [--t0 0] [--t1 20] [--frames 161]

writes OUT_DIR/field.tvff; every tvf command that takes a generated folder reads it.
"""
import argparse
import json
import os
import struct

import numpy as np

A, EPS, OMEGA = 0.1, 0.25, 2 * np.pi / 10


def velocity(x, y, t):
    a = EPS * np.sin(OMEGA * t)
    b = 1 - 2 * a
    f = a * x * x + b * x
    df = 2 * a * x + b
    return (-np.pi * A * np.sin(np.pi * f) * np.cos(np.pi * y),
            np.pi * A * np.cos(np.pi * f) * np.sin(np.pi * y) * df)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("out")
    p.add_argument("--nx", type=int, default=101)
    p.add_argument("--ny", type=int, default=51)
    p.add_argument("--t0", type=float, default=0.0)
    p.add_argument("--t1", type=float, default=20.0)
    p.add_argument("--frames", type=int, default=161)
    o = p.parse_args()

    xs = np.linspace(0.0, 2.0, o.nx)
    ys = np.linspace(0.0, 1.0, o.ny)
    X, Y = np.meshgrid(xs, ys)  # row iy, column ix: vertex iy*nx + ix
    positions = np.stack([X.ravel(), Y.ravel(), np.zeros(X.size)], axis=1).astype("<f8")
    ix, iy = np.meshgrid(np.arange(o.nx - 1), np.arange(o.ny - 1))
    v00 = (iy * o.nx + ix).ravel()
    v10, v01 = v00 + 1, v00 + o.nx
    v11 = v01 + 1
    faces = np.empty((2 * v00.size, 3), dtype="<i4")
    faces[0::2] = np.stack([v00, v10, v11], axis=1)
    faces[1::2] = np.stack([v00, v11, v01], axis=1)
    times = np.linspace(o.t0, o.t1, o.frames)
    field = np.empty((o.frames, positions.shape[0], 2), dtype="<f8")
    for j, t in enumerate(times):
        u, v = velocity(positions[:, 0], positions[:, 1], t)
        field[j, :, 0], field[j, :, 1] = u, v

    header = json.dumps({"vertices": int(positions.shape[0]), "faces": int(faces.shape[0]),
                         "frames": o.frames, "t0": o.t0, "t1": o.t1, "scene": None}).encode()
    preamble = 8 + 4 + 8
    header += b" " * ((8 - (preamble + len(header)) % 8) % 8)  # arrays 8-byte aligned
    os.makedirs(o.out, exist_ok=True)
    path = os.path.join(o.out, "field.tvff")
    with open(path + ".tmp", "wb") as out:
        out.write(b"TVFFIELD")
        out.write(struct.pack("<IQ", 1, len(header)))
        out.write(header)
        out.write(positions.tobytes())
        out.write(faces.tobytes())
        out.write(field.tobytes())
    os.replace(path + ".tmp", path)
    print(f"wrote {path}: {positions.shape[0]} vertices, {o.frames} frames on [{o.t0}, {o.t1}]")


if __name__ == "__main__":
    main()
