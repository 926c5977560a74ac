#!/usr/bin/env python3
"""The picture of example 15 (docs/images/incompressible_15.png): the designed field and
its incompressible projection side by side on the sphere, one frame.

    /usr/bin/python3 examples/15_incompressible_sphere/picture.py build/release/tvf out.png [FRAME]

Generates the scene twice (as designed, with "incompressible" removed, and as written),
then draws each: an orthographic view, faces coloured by the divergence of the field's
linear interpolant in each face (computed here from field.npy, independently of tvf: red
out, blue in, one scale for both), arrows along the field. Needs numpy and matplotlib
(Debian: python3-numpy, python3-matplotlib)."""
import json
import os
import subprocess
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402


def generate(tvf, scene, out):
    subprocess.run([tvf, "generate", scene, "-o", out, "--no-vtk", "--quiet"], check=True)
    return (np.load(os.path.join(out, "vertices.npy")), np.load(os.path.join(out, "faces.npy")),
            np.load(os.path.join(out, "field.npy")))


def face_divergence(x, f, v):
    """Divergence of the linear interpolant of the vectors (projected into each face)."""
    a, b, c = x[f[:, 0]], x[f[:, 1]], x[f[:, 2]]
    n = np.cross(b - a, c - a)
    area2 = np.linalg.norm(n, axis=1)
    n /= area2[:, None]
    div = np.zeros(len(f))
    for k in range(3):
        e = x[f[:, (k + 2) % 3]] - x[f[:, (k + 1) % 3]]       # edge opposite corner k, ccw
        grad = np.cross(n, e) / area2[:, None]                  # ∇λ_k
        vk = v[f[:, k]]
        vk = vk - (vk * n).sum(1)[:, None] * n
        div += (grad * vk).sum(1)
    return div, n


def draw(ax, x, f, v, div, vmax, title):
    view = np.array([1.0, -1.2, 0.8]); view /= np.linalg.norm(view)
    right = np.cross([0, 0, 1.0], view); right /= np.linalg.norm(right)
    up = np.cross(view, right)
    proj = np.stack([x @ right, x @ up], 1)
    _, n = face_divergence(x, f, v)
    visible = n @ view > 0
    order = np.argsort((x[f].mean(1) @ view)[visible])
    fv = f[visible][order]
    light = np.array([0.3, -0.5, 1.0]); light /= np.linalg.norm(light)
    shade = 0.55 + 0.45 * np.clip(n[visible][order] @ light, 0, 1)
    cmap = plt.get_cmap("RdBu_r")
    colours = cmap(0.5 + 0.5 * np.clip(div[visible][order] / vmax, -1, 1))
    colours[:, :3] *= shade[:, None]
    ax.add_collection(PolyCollection(proj[fv], facecolors=colours, edgecolors="none"))
    # Arrows at the first 642 vertices (an icosphere keeps its coarser levels' vertices
    # first, so these are evenly spread), on the front half, length by speed.
    front = np.nonzero(x[:642] @ view > 0.15)[0]
    pv = np.stack([v[front] @ right, v[front] @ up], 1)
    speed = np.linalg.norm(v[front], axis=1)
    scale = np.percentile(np.linalg.norm(v, axis=1), 90) + 1e-12
    pv = pv / scale * 0.11
    ax.quiver(proj[front, 0] - 0.5 * pv[:, 0], proj[front, 1] - 0.5 * pv[:, 1], pv[:, 0], pv[:, 1], angles="xy",
              scale_units="xy", scale=1, width=0.0045, headwidth=3.5, headlength=4, headaxislength=3.5,
              color="#202020")
    ax.set_xlim(-1.05, 1.05); ax.set_ylim(-1.05, 1.05); ax.set_aspect("equal"); ax.axis("off")
    ax.set_title(title, fontsize=10)


def main():
    tvf, out_png = sys.argv[1], sys.argv[2]
    frame = int(sys.argv[3]) if len(sys.argv) > 3 else 50
    here = os.path.dirname(os.path.abspath(__file__))
    scene = json.load(open(os.path.join(here, "scene.json")))
    with tempfile.TemporaryDirectory() as tmp:
        plain = dict(scene); plain.pop("incompressible", None)
        plain_path = os.path.join(tmp, "plain.json")
        json.dump(plain, open(plain_path, "w"))
        x, f, before = generate(tvf, plain_path, os.path.join(tmp, "plain"))
        _, _, after = generate(tvf, os.path.join(here, "scene.json"), os.path.join(tmp, "incompressible"))
        report = json.load(open(os.path.join(tmp, "incompressible", "divergence.json")))
    d0, _ = face_divergence(x, f, before[frame].astype(np.float64))
    d1, _ = face_divergence(x, f, after[frame].astype(np.float64))
    vmax = np.percentile(np.abs(d0), 98)
    fig, axes = plt.subplots(1, 2, figsize=(8, 4.2), dpi=100)
    t = report["times"][frame]
    draw(axes[0], x, f, before[frame], d0, vmax,
         f"designed, t = {t:.2f}: RMS div {report['before'][frame]:.2f}")
    draw(axes[1], x, f, after[frame], d1, vmax,
         f"incompressible: RMS div {report['after'][frame]:.1e}")
    fig.tight_layout()
    fig.savefig(out_png)
    print(f"wrote {out_png}; face divergence (this script's own estimate) RMS "
          f"{np.sqrt((d0 ** 2).mean()):.3f} before, {np.sqrt((d1 ** 2).mean()):.3f} after")


if __name__ == "__main__":
    main()
