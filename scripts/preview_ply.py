#!/usr/bin/env python3
"""Quick look at a per-vertex coloured PLY written by `tvf render synth|terrain --meshes`:
an orthographic point-splat picture with a z-buffer and Lambert shading (NumPy only).

This is a preview for checking results and for the docs until the mesh renderer is merged;
it is not tvf's surface renderer.

    scripts/preview_ply.py MESH.ply OUT.png [--size 400] [--view x,y,z] [--up x,y,z]
"""
import argparse
import struct
import sys
import zlib

import numpy as np


def read_ply(path):
    with open(path, "rb") as f:
        header = []
        while True:
            line = f.readline().decode("ascii").strip()
            header.append(line)
            if line == "end_header":
                break
        nv = nf = 0
        for line in header:
            if line.startswith("element vertex"):
                nv = int(line.split()[2])
            if line.startswith("element face"):
                nf = int(line.split()[2])
        if "format binary_little_endian 1.0" not in header:
            sys.exit(f"{path}: expected a binary PLY written by tvf")
        vdt = np.dtype([("p", "<f4", 3), ("c", "u1", 3)])
        verts = np.frombuffer(f.read(nv * vdt.itemsize), dtype=vdt)
        fdt = np.dtype([("n", "u1"), ("i", "<i4", 3)])
        faces = np.frombuffer(f.read(nf * fdt.itemsize), dtype=fdt)
    return verts["p"].astype(float), verts["c"].astype(float) / 255.0, faces["i"]


def write_png(path, rgb):
    h, w, _ = rgb.shape
    raw = b"".join(b"\x00" + rgb[y].tobytes() for y in range(h))
    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)
    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(png)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mesh")
    ap.add_argument("out")
    ap.add_argument("--size", type=int, default=400)
    ap.add_argument("--view", default="0.3,-1,0.5", help="direction from the object to the eye")
    ap.add_argument("--up", default="0,0,1")
    a = ap.parse_args()
    p, c, f = read_ply(a.mesh)
    # Vertex normals from the faces.
    n = np.zeros_like(p)
    fn = np.cross(p[f[:, 1]] - p[f[:, 0]], p[f[:, 2]] - p[f[:, 0]])
    for k in range(3):
        np.add.at(n, f[:, k], fn)
    n /= np.linalg.norm(n, axis=1, keepdims=True) + 1e-30
    view = np.array([float(x) for x in a.view.split(",")]); view /= np.linalg.norm(view)
    up = np.array([float(x) for x in a.up.split(",")])
    right = np.cross(up, view); right /= np.linalg.norm(right)
    up = np.cross(view, right)
    q = p - p.mean(axis=0)
    x, y, z = q @ right, q @ up, q @ view
    extent = max(x.max() - x.min(), y.max() - y.min()) * 1.05
    s = a.size / extent
    px = ((x - x.mean()) * s + a.size / 2).astype(int)
    py = ((y.mean() - y) * s + a.size / 2).astype(int)
    light = view + 0.5 * up; light /= np.linalg.norm(light)
    shade = np.clip(0.35 + 0.65 * (n @ light), 0, 1)
    facing = n @ view > -0.1
    # Splat radius from the mean edge length.
    e = np.linalg.norm(p[f[:, 0]] - p[f[:, 1]], axis=1).mean()
    r = max(1, int(np.ceil(0.7 * e * s)))
    img = np.ones((a.size, a.size, 3))
    depth = np.full((a.size, a.size), -np.inf)
    order = np.argsort(z)
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            if dx * dx + dy * dy > r * r:
                continue
            xx, yy = px[order] + dx, py[order] + dy
            ok = facing[order] & (xx >= 0) & (xx < a.size) & (yy >= 0) & (yy < a.size)
            idx = order[ok]
            xx, yy = xx[ok], yy[ok]
            zz = z[idx]
            nearer = zz > depth[yy, xx]
            idx, xx, yy, zz = idx[nearer], xx[nearer], yy[nearer], zz[nearer]
            depth[yy, xx] = zz  # later (nearer) splats win: the order is by depth
            img[yy, xx] = c[idx] * shade[idx, None]
    write_png(a.out, (np.clip(img, 0, 1) * 255).astype(np.uint8))


if __name__ == "__main__":
    main()
