"""Velocity grids (OpenVDB) and PLY meshes with vx, vy, vz per frame, for Houdini and
Blender (docs/user_guide.md, "Export for Houdini and Blender").

    PYTHONPATH=build/release/python python3 examples/python/export_for_houdini.py
"""
import tvf

planar = tvf.generate("examples/02_combined_elements/scene.json")
print(len(planar.export_vdb("out/vdb")), "VDB files in out/vdb")       # planar grids only
sphere = tvf.generate("examples/03_sphere_vortex/scene.json")
print(len(sphere.export_ply("out/ply")), "PLY files in out/ply")       # any domain
