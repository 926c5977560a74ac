"""Streamlines and pathlines of a generated field, drawn with matplotlib when it is there.

    PYTHONPATH=build/release/python python3 examples/python/curves.py
"""
import tvf

f = tvf.generate("examples/02_combined_elements/scene.json")
lines = [f.streamline([x, y], t=0.5) for x in (-0.6, 0.0, 0.6) for y in (-0.6, 0.0, 0.6)]
path = f.pathline([0.0, -0.5], t_start=0.0, t_end=1.0)
print(len(lines), "streamlines;", "pathline of", len(path["points"]), "points, stopped by", path["stop"])
try:
    import matplotlib.pyplot as plt
except ImportError:
    print("(install python3-matplotlib to see them)")
    raise SystemExit(0)
for s in lines:
    plt.plot(s["points"][:, 0], s["points"][:, 1], "k-", lw=0.8)
plt.plot(path["points"][:, 0], path["points"][:, 1], "r-", lw=2)
plt.gca().set_aspect("equal")
plt.savefig("curves.png", dpi=120)
print("wrote curves.png")
