#!/usr/bin/env python3
"""Key-frame topology on CGAL's sample meshes: is the knot guided, and if not, why.

For each mesh of libcgal-demo's data archive named on the command line (default: cow,
mushroom, camel, man, bear, elephant) this writes the knot of examples/26 (a source and a
center trading places, 32 frames, solver.keyframe_topology "matched") on the mesh's flank,
runs `tvf generate` and `tvf analyze`, and prints one table row: singularities matched,
the longest carry (chord over the bounding box's diagonal), how the paths were routed,
guided or the reason it fell back, events the analysis finds that were not asked for
(the design check's count, Hopf events included since session 20) and how many of them are
Hopf events (the knot asks for none), and the CPU seconds of `tvf generate`.

    /usr/bin/python3 bench/keyframe_topology_meshes.py --tvf build/release/tvf [--out DIR] [MESH ...]

The flank: the vertex whose normal points most along the bounding box's thinnest axis,
near the middle of its longest; the second point a fraction (--apart, of the box's
diagonal) away along the longest axis among vertices facing the same way. region_radius
is 0.05 of the diagonal (path_separation defaults to twice that) unless --region says
otherwise.
"""
import argparse
import json
import re
import resource
import subprocess
import sys
import tarfile
from pathlib import Path

import numpy as np

ARCHIVE = "/usr/share/doc/libcgal-dev/data.tar.gz"


def load_off(path):
    words = [w for line in path.read_text().splitlines() if not line.startswith("#") for w in line.split()]
    if words[0] != "OFF":
        sys.exit(f"{path}: not an OFF file")
    nv, nf = int(words[1]), int(words[2])
    at = 4
    v = np.array(words[at:at + 3 * nv], dtype=float).reshape(nv, 3)
    at += 3 * nv
    faces = []
    for _ in range(nf):
        k = int(words[at])
        faces.append([int(x) for x in words[at + 1:at + 1 + k]][:3])
        at += 1 + k
    return v, np.array(faces)


def knot_scene(mesh, apart, region):
    v, f = load_off(mesh)
    ext = v.max(0) - v.min(0)
    diag = float(np.linalg.norm(ext))
    side, longest = int(np.argmin(ext)), int(np.argmax(ext))
    n = np.zeros_like(v)
    fn = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    for k in range(3):
        np.add.at(n, f[:, k], fn)
    n /= np.linalg.norm(n, axis=1)[:, None] + 1e-30
    mid = (v.max(0) + v.min(0)) / 2
    a = int(np.argmax(n[:, side] - 2 * abs(v[:, longest] - mid[longest]) / ext[longest]))
    d = apart * diag
    dist = np.linalg.norm(v - v[a], axis=1)
    facing = np.where((n[:, side] > 0.7) & (abs(dist - d) < 0.1 * d))[0]
    if len(facing) == 0:
        return None
    b = int(facing[np.argmax(abs(v[facing, longest] - v[a, longest]))])
    p, q = v[a].tolist(), v[b].tolist()
    return {
        "tvf": 1,
        "description": f"The knot of examples/26 on CGAL's {mesh.stem} (bench/keyframe_topology_meshes.py).",
        "domain": {"mesh": str(mesh)},
        "time": {"frames": 32, "range": [0, 1]},
        "generator": "spacetime",
        "solver": {"region_radius": round(region * diag, 4), "keyframe_topology": "matched"},
        "falloff": 20,
        "keyframes": [
            {"t": 0, "elements": [{"kind": "singular", "type": "source", "at": p},
                                  {"kind": "singular", "type": "ccw_center", "at": q}]},
            {"t": 1, "elements": [{"kind": "singular", "type": "source", "at": q},
                                  {"kind": "singular", "type": "ccw_center", "at": p}]},
        ],
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("meshes", nargs="*", default=["cow", "mushroom", "camel", "man", "bear", "elephant"])
    ap.add_argument("--tvf", default="build/release/tvf")
    ap.add_argument("--out", default="out/keyframe_topology_meshes")
    ap.add_argument("--apart", type=float, default=0.15, help="the knot's two points, a fraction of the diagonal apart")
    ap.add_argument("--region", type=float, default=0.05, help="region_radius, a fraction of the diagonal")
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    try:
        with tarfile.open(ARCHIVE) as tar:
            for m in args.meshes:
                tar.extract(f"data/meshes/{m}.off", out)
    except (OSError, KeyError) as e:
        sys.exit(f"{ARCHIVE}: {e} (Debian package libcgal-demo)")
    print("| mesh | vertices | matched | longest carry | routing | guided | why not | events not asked for | of them Hopf | generate CPU s |")
    print("|---|---:|---:|---:|---|---|---|---:|---:|---:|")
    for m in args.meshes:
        mesh = (out / "data/meshes" / f"{m}.off").resolve()
        scene = knot_scene(mesh, args.apart, args.region)
        if scene is None:
            print(f"| {m} | | | | no second point on the flank | | | | |")
            continue
        path = out / f"{m}.json"
        path.write_text(json.dumps(scene, indent=1))
        field = out / m
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        gen = subprocess.run([args.tvf, "generate", str(path), "-o", str(field), "--no-vtk"],
                             capture_output=True, text=True)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
        if gen.returncode != 0:
            print(f"| {m} | | | | generate failed: {gen.stderr.strip().splitlines()[-1]} | | | | {cpu:.1f} |")
            continue
        interval = json.loads((field / "keyframe_topology.json").read_text())["intervals"][0]
        ana = subprocess.run([args.tvf, "analyze", str(field), "-o", str(field / "analysis.json"), "--no-plots"],
                             capture_output=True, text=True)
        extra = re.search(r"(\d+) not asked for", ana.stdout)
        # The knot designs no Hopf element and changes no node's stability, so every Hopf
        # event the analysis finds (a carried center turned into a focus with limit cycles)
        # is among those not asked for.
        try:
            hopf = str(sum(b.get("kind") == "hopf"
                           for b in json.loads((field / "analysis.json").read_text())["bifurcations"]))
        except (OSError, ValueError, KeyError):
            hopf = "?"
        nv = len(load_off(mesh)[0])
        why = interval.get("unguided_reason", "")
        # A collision: which two, when, and how close against what they must keep
        # (keyframe_topology.json's collision_at; the sentence is in "collision").
        if "collision_at" in interval:
            c = interval["collision_at"]
            other = "a pair's template" if c["template"] else f"a {c['types'][1]}"
            why = (f"collision at t = {c['t']:.3f}: a {c['types'][0]} and {other} come {c['distance']:.3g} apart, "
                   f"{c['required']:.3g} asked")
        # The longest chord a matched singularity is carried, over the mesh's bounding-box
        # diagonal (the designed pair's is --apart).
        v = load_off(mesh)[0]
        diag = float(np.linalg.norm(v.max(0) - v.min(0)))
        longest = max((np.linalg.norm(np.subtract(x["to"], x["from"])) for x in interval["matched"]), default=0.0)
        print(f"| {m} | {nv} | {len(interval['matched'])} | {longest / diag:.2f} | {interval['routing']} | "
              f"{'yes' if interval['guided'] else 'no'} | {why} | {extra.group(1) if extra else '?'} | {hopf} | {cpu:.1f} |")


if __name__ == "__main__":
    main()
