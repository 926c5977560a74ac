"""The stateful form: build a scene as a dict, generate with progress, edit, undo, save.

    PYTHONPATH=build/release/python python3 examples/python/design_and_edit.py
"""
import sys

import numpy as np

import tvf

scene = {
    "tvf": 1,
    "domain": {"grid": {"size": [33, 33], "min": [-1, -1], "max": [1, 1]}},
    "time": {"frames": 21, "range": [0, 1]},
    "generator": "constrained",
    "solver": {"region_radius": 0.15},
    "falloff": 20,
    "elements": [
        {"kind": "regular", "pathline": [[-0.9, -0.3, 0], [-0.8, -0.3, 1]]},
        {"kind": "singular", "jacobian": [[-1, 0], [0, 1]], "path": [[-0.3, -0.3, 0], [-0.25, -0.3, 1]]},
        {"kind": "singular", "type": "source", "path": [[0.2, -0.3, 0]]},
        {"kind": "singular", "type": "ccw_center", "path": [[0.1, 0.6, 0]]},
    ],
}


def progress(done, total):
    print(f"\r{done}/{total} frames", end="", file=sys.stderr)


d = tvf.Design(scene)
before = d.generate(progress=progress).vectors.copy()   # Ctrl-C cancels the solve
print(file=sys.stderr)
print("singularities at frame 10:", [s["type"] for s in d.analyze()["singularities"] if s["frame"] == 10])

# Cancel the saddle-source pair at frame 10 (a refused edit raises ValueError, changing nothing).
try:
    print(d.edit(op="cancel", frame=10, pair=[[-0.27, -0.3], [0.2, -0.3]])["summary"])
    print("after:", [s["type"] for s in d.analyze()["singularities"] if s["frame"] == 10])
except ValueError as e:
    print("refused:", e)

d.edit(op="smooth", strength=0.3)
print("edits:", [e["op"] for e in d.scene["edits"]])
d.undo()
print("after undo:", [e["op"] for e in d.scene["edits"]])
print("largest change from the unedited field:", float(np.abs(d.field.vectors - before).max()))
d.save("my_edited_scene.json")  # the scene with its edits; `tvf generate` makes the same field
