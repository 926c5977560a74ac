"""Lagrangian views of the double gyre (examples/22) from Python: the FTLE field at t = 10
(horizon 10, both ways: the windows [0, 10] and [10, 20] fit the time range), a streakline
and a timeline, drawn with matplotlib when it is there.

    python3 examples/22_double_gyre_ftle/make_double_gyre.py out/gyre
    PYTHONPATH=build/release/python python3 examples/python/lagrangian.py out/gyre
"""
import sys

import numpy as np

import tvf

f = tvf.load(sys.argv[1] if len(sys.argv) > 1 else "out/gyre")
frame = int(np.argmin(np.abs(f.times - 10.0)))
r = f.ftle(10.0, frames=[frame])                   # forward: repelling LCS; backward: attracting
forward, backward = r["forward"][frame], r["backward"][frame]
x, y = f.vertices[:, 0], f.vertices[:, 1]
# The repelling LCS on the row y = 0.3, away from the walls (bright too: particles slide along them).
row = (np.abs(y - 0.3) < 1e-9) & (x > 0.1) & (x < 1.9)
ridge = np.argmax(np.where(row, forward, -np.inf))
print(f"FTLE at t = {f.times[frame]:g}, T = 10: forward up to {np.nanmax(forward):.3f}, its ridge on y = 0.3 "
      f"at x = {x[ridge]:.2f}; backward up to {np.nanmax(backward):.3f}")
streak = f.streakline([1.0, 0.3], 0.0, 10.0)       # dye released at (1, 0.3) over [0, 10]
line = f.timeline([0.1, 0.5], [1.9, 0.5], 0.0, 10.0)  # y = 0.5 at t = 0, carried to t = 10
print(f"streakline: {streak['released']} particles, {streak['left']} left; "
      f"timeline: {len(line['points'])} particles after refinement")
try:
    import matplotlib.pyplot as plt
except ImportError:
    print("(install python3-matplotlib to see them)")
    raise SystemExit(0)
fig, ax = plt.subplots(figsize=(10, 5))
ax.tripcolor(x, y, f.faces, np.nan_to_num(forward), shading="gouraud", cmap="magma")
ax.plot(streak["points"][:, 0], streak["points"][:, 1], "c-", lw=1)
ax.plot(line["points"][:, 0], line["points"][:, 1], "w-", lw=0.8)
ax.set_aspect("equal")
fig.savefig("lagrangian.png", dpi=100)
print("wrote lagrangian.png")
