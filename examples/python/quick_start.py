"""The README's Python quick start: generate a scene, look at the arrays, analyse it.

    PYTHONPATH=build/release/python python3 examples/python/quick_start.py
"""
import tvf

f = tvf.generate("examples/02_combined_elements/scene.json")  # a scene file or a dict
print(f)                                   # <tvf.Field 100 frames x 4225 vertices, planar>
print(f.vectors.shape, f.vectors.dtype)    # (100, 4225, 3) float32: the values of field.npy
print(f.vertices.shape, f.faces.shape, f.times[:3])
a = tvf.analyze(f)                          # the analysis JSON of `tvf analyze` as dicts and lists
print(len(a["paths"]), "singularity paths,", len(a["bifurcations"]), "bifurcations")
print("types at t = 0:", sorted({s["type"] for s in a["singularities"] if s["frame"] == 0}))
