"""tvf: design of time-varying vector fields on planar grids and triangle-mesh surfaces.

Quick start::

    import tvf
    f = tvf.generate("examples/02_combined_elements/scene.json")   # or a scene dict
    print(f.vectors.shape)          # (frames, vertices, 3) world vectors, as field.npy
    a = tvf.analyze(f)              # singularities, paths, bifurcations, coherence

Domains can be numpy arrays (`tvf.generate(scene, vertices=V, faces=F)`), and
`tvf.render_texture(f, 256, frames=[0, 5])` gives texture animation pictures as
(H, W, 3) uint8 arrays. `tvf.Design(scene)` is the stateful form: change the scene, generate, analyze, edit,
undo. Bad input raises ValueError with the command line's sentence and the place as
attributes (file, json_path, line, column). See
docs/user_guide.md ("Python") and examples/python/.
"""
from ._tvf import (  # noqa: F401
    Cancelled,
    Design,
    Field,
    analyze,
    export_ply,
    export_vdb,
    generate,
    load,
    render_texture,
    vdb_available,
)

__all__ = ["Cancelled", "Design", "Field", "analyze", "export_ply", "export_vdb", "generate", "load",
           "render_texture", "vdb_available"]
