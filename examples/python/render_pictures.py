"""Texture animation pictures as numpy arrays (H x W x 3 uint8), without files, on a
planar grid and on a surface; and the same pictures written as PNG frames where asked.

    PYTHONPATH=build/release/python python3 examples/python/render_pictures.py [OUT_DIR]
"""
import os
import sys

import numpy as np

import tvf

out = sys.argv[1] if len(sys.argv) > 1 else "pictures"

# Planar: the combined-elements example at 256 pixels, pictures 0 and 5 only.
f = tvf.generate("examples/02_combined_elements/scene.json")
first, sixth = tvf.render_texture(f, 256, frames=[0, 5])
print("planar:", first.shape, first.dtype, "mean", round(float(first.mean()), 1),
      "| changed pixels 0 -> 5:", int((first != sixth).any(axis=2).sum()))

# With the singularities drawn over, and written as PNG frames too (pictures 0 to 5).
_, marked = tvf.render_texture(f, 256, frames=[0, 5], overlay=["singularities"], frames_dir=f"{out}/planar")
print("overlay: the dots change", int((marked != sixth).any(axis=2).sum()), "pixels of picture 5; PNGs in",
      f"{out}/planar")

# A surface: the sphere vortex example at 8 frames, seen from the side.
sphere = tvf.generate({**tvf.Design("examples/03_sphere_vortex/scene.json").scene,
                       "time": {"frames": 8, "range": [0, 1]}})
pictures = tvf.render_texture(sphere, 256, frames=[0, 7], view=[1, -0.6, 0.3], frames_dir=f"{out}/sphere")
background = (pictures[1] == 255).all(axis=2).mean()
print("surface:", pictures[1].shape, f"{background:.0%} background; PNGs in", f"{out}/sphere")

# A long animation stopped from its progress callback: returning False raises
# tvf.Cancelled before the next picture, and the frame folder is not left half written.
def stop_after_three(done, total):
    return done < 3


try:
    tvf.render_texture(f, 256, frames=[0, 399], pictures=400, frames_dir=f"{out}/stopped",
                       progress=stop_after_three)
except tvf.Cancelled as e:
    print("stopped:", e, "| folder written:", os.path.exists(f"{out}/stopped"))

# Arrays go straight to matplotlib (imshow) or imageio where those are installed.
try:
    import matplotlib.pyplot as plt
except ImportError:
    print("(install python3-matplotlib to see them side by side)")
    raise SystemExit(0)
fig, axes = plt.subplots(1, 2, figsize=(8, 4))
for ax, p in zip(axes, (sixth, pictures[1])):
    ax.imshow(p)
    ax.axis("off")
fig.savefig(f"{out}/side_by_side.png", dpi=100)
print("wrote", f"{out}/side_by_side.png")
