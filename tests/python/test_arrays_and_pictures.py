"""Domains from numpy arrays, texture pictures as numpy arrays, and the type stub
(issue 18, Python): a mesh given as arrays gives exactly the field of the same mesh read
from a file, broken arrays are refused with the mesh file's sentences, pictures are the
pixels `tvf render texture` writes, and the stub names everything the module has.

Run by ctest with the rest of tests/python (PYTHONPATH=BUILD/python, TVF_CLI)."""
import ast
import json
import os
import shutil
import struct
import subprocess
import zlib
from pathlib import Path

import numpy as np
import pytest

import tvf

TVF = os.environ.get("TVF_CLI", "tvf")


def cli(*args):
    run = subprocess.run([TVF, *map(str, args)], capture_output=True, text=True)
    return run.returncode, run.stdout + run.stderr


def icosphere(subdivisions):
    """An icosphere made in numpy: the icosahedron, each triangle split in four and the new
    vertices pushed onto the unit sphere, `subdivisions` times (10*4^s + 2 vertices)."""
    p = (1 + 5 ** 0.5) / 2
    v = [(-1, p, 0), (1, p, 0), (-1, -p, 0), (1, -p, 0), (0, -1, p), (0, 1, p), (0, -1, -p), (0, 1, -p),
         (p, 0, -1), (p, 0, 1), (-p, 0, -1), (-p, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
         (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11),
         (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    verts = [np.array(x, float) / np.linalg.norm(x) for x in v]
    for _ in range(subdivisions):
        mids, faces = {}, []

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in mids:
                m = verts[a] + verts[b]
                verts.append(m / np.linalg.norm(m))
                mids[key] = len(verts) - 1
            return mids[key]

        for a, b, c in f:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            faces += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = faces
    return np.array(verts), np.array(f, dtype=np.int64)


def planar_grid(n, lo=-1.0, hi=1.0):
    """An n x n vertex grid over [lo, hi]^2 at z = 0, each cell cut into two triangles."""
    x = np.linspace(lo, hi, n)
    xx, yy = np.meshgrid(x, x)
    v = np.stack([xx.ravel(), yy.ravel(), np.zeros(n * n)], axis=1)
    idx = np.arange(n * n).reshape(n, n)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel(), idx[1:, :-1].ravel()
    f = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return v, f


def write_obj(path, v, f):
    with open(path, "w") as out:
        for p in v:
            out.write("v {!r} {!r} {!r}\n".format(*map(float, p)))
        for t in f:
            out.write("f {} {} {}\n".format(*(int(i) + 1 for i in t)))


def read_png(path):
    """RGB pixels of an 8-bit, non-interlaced PNG (what Cairo writes), as (H, W, 3) uint8."""
    data = Path(path).read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, chunks = 8, {}
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        chunks.setdefault(kind, b"")
        chunks[kind] += data[pos + 8:pos + 8 + n]
        pos += 12 + n
    w, h, depth, color, _, _, interlace = struct.unpack(">IIBBBBB", chunks[b"IHDR"])
    assert depth == 8 and interlace == 0 and color in (2, 6)
    bpp = 3 if color == 2 else 4
    raw = zlib.decompress(chunks[b"IDAT"])
    stride = w * bpp
    out = np.zeros((h, stride), np.int32)
    prev = np.zeros(stride, np.int32)
    for y in range(h):
        kind = raw[y * (stride + 1)]
        line = np.frombuffer(raw, np.uint8, stride, y * (stride + 1) + 1).astype(np.int32)
        cur = np.zeros(stride, np.int32)
        for i in range(stride):
            a = cur[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if kind == 0:
                pred = 0
            elif kind == 1:
                pred = a
            elif kind == 2:
                pred = b
            elif kind == 3:
                pred = (a + b) // 2
            else:
                pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
            cur[i] = (line[i] + pred) & 0xFF
        out[y] = cur
        prev = cur
    return out.reshape(h, w, bpp)[:, :, :3].astype(np.uint8)


SPHERE_SCENE = {
    "tvf": 1,
    "time": {"frames": 3, "range": [0, 1]},
    "generator": "basis",
    "falloff": 4,
    "elements": [{"kind": "singular", "type": "source", "path": [[0, 0, 1, 0]]}],
}

GRID_SCENE = {
    "tvf": 1,
    "time": {"frames": 6, "range": [0, 1]},
    "generator": "basis",
    # A mesh domain, even a planar one, takes [x, y, z, t] points (as a mesh file does).
    "elements": [{"kind": "singular", "type": "source", "path": [[0, 0, 0, 0]]}],
}


# ---- domains from numpy ----

def test_icosphere_from_arrays_gives_the_field_of_the_same_mesh_file(tmp_path):
    v, f = icosphere(2)
    assert v.shape == (162, 3) and f.shape == (320, 3)
    field = tvf.generate(SPHERE_SCENE, vertices=v, faces=f)
    assert not field.planar
    assert field.vectors.shape == (3, 162, 3)
    # The arrays are the domain as given: nothing reordered or repaired.
    assert np.array_equal(field.vertices, v)
    assert np.array_equal(field.faces, f)
    # The same mesh as a file gives the same numbers.
    write_obj(tmp_path / "ico.obj", v, f)
    from_file = tvf.generate({**SPHERE_SCENE, "domain": {"mesh": str(tmp_path / "ico.obj")}})
    assert np.array_equal(from_file.vertices, v)
    assert np.array_equal(from_file.vectors, field.vectors)
    # Tangent to the sphere, and a source at the north pole: a sink at the south pole
    # (Poincaré–Hopf: indices sum to 2).
    normals = np.cross(field.e1, field.e2)
    assert np.abs(np.einsum("jvk,vk->jv", field.vectors, normals)).max() < 1e-6
    assert np.all(np.einsum("vk,vk->v", normals, v) > 0.99)  # the vertex normals point outwards
    a = tvf.analyze(field)
    first = [s for s in a["singularities"] if s["frame"] == 0]
    assert sorted(s["type"] for s in first) == ["sink", "source"]
    source = next(s for s in first if s["type"] == "source")
    sink = next(s for s in first if s["type"] == "sink")
    edge = np.linalg.norm(v[f[:, 0]] - v[f[:, 1]], axis=1).mean()
    assert np.linalg.norm(np.array(source["position"]) - [0, 0, 1]) < 0.05
    assert np.linalg.norm(np.array(sink["position"]) - [0, 0, -1]) < edge


def test_planar_grid_from_arrays_is_planar_and_radial():
    v, f = planar_grid(17)
    field = tvf.generate(GRID_SCENE, vertices=v, faces=f.astype(np.int32))
    assert field.planar
    assert np.array_equal(field.vertices, v)
    # A lone source at the origin: every vector points straight away from it.
    w = field.vectors[0].astype(float)
    cross = w[:, 0] * v[:, 1] - w[:, 1] * v[:, 0]
    assert np.abs(cross).max() < 1e-6 * np.abs(w).max()
    away = (w[:, :2] * v[:, :2]).sum(1)
    assert np.all(away[np.linalg.norm(v, axis=1) > 0] > 0)
    assert np.all(w[:, 2] == 0)


def test_design_on_arrays_keeps_the_mesh_through_scene_changes_and_undo(tmp_path):
    v, f = icosphere(1)
    d = tvf.Design(SPHERE_SCENE, vertices=v, faces=f)
    assert d.scene["domain"] == {"mesh": "vertices/faces"}
    first = d.generate().vectors.copy()
    moved = d.scene
    moved["elements"][0]["path"] = [[1, 0, 0, 0]]
    d.scene = moved
    assert np.array_equal(d.generate().vertices, v)
    assert not np.array_equal(d.field.vectors, first)
    d.undo()
    assert np.array_equal(d.generate().vectors, first)
    # Saved, the scene names a mesh file written beside it, and loads again on its own.
    path = tmp_path / "on_arrays.json"
    d.save(str(path))
    assert json.loads(path.read_text())["domain"] == {"mesh": "on_arrays.mesh.off"}
    again = tvf.generate(str(path))
    assert np.array_equal(again.vertices, v) and np.array_equal(again.faces, f)
    assert np.array_equal(again.vectors, first)
    # A scene dict with its own domain: the arrays replace it.
    assert tvf.Design({**SPHERE_SCENE, "domain": {"grid": {"size": [5, 5]}}}, vertices=v,
                      faces=f).generate().vectors.shape == (3, 42, 3)


def broken_meshes():
    v, f = icosphere(1)
    out_of_range = f.copy()
    out_of_range[7, 1] = 42
    nan = v.copy()
    nan[3, 2] = np.nan
    # A fin: a third triangle on the edge 0-11 of the first face (non-manifold edge).
    fin_v = np.vstack([v, [[0.0, 0.0, 0.0]]])
    fin_f = np.vstack([f, [[0, 11, 42]]])
    return {
        "out of range": (v, out_of_range, "face 7 uses vertex 42, but the vertices are numbered 0 to 41"),
        "nan": (nan, f, "vertex 3 has a non-finite coordinate"),
        "non-manifold": (fin_v, fin_f, "(non-manifold"),
    }


@pytest.mark.parametrize("case", ["out of range", "nan", "non-manifold"])
def test_broken_arrays_are_refused_with_the_mesh_sentence(case):
    v, f, sentence = broken_meshes()[case]
    with pytest.raises(ValueError) as e:
        tvf.generate(SPHERE_SCENE, vertices=v, faces=f)
    assert str(e.value).startswith("vertices/faces: ")
    assert sentence in str(e.value)
    assert e.value.file == "vertices/faces"
    with pytest.raises(ValueError, match="^vertices/faces: "):
        tvf.Design(SPHERE_SCENE, vertices=v, faces=f)


def test_broken_arrays_say_what_a_broken_file_says(tmp_path):
    # The non-manifold fin as an OBJ: the file's sentence after its name is the arrays'.
    v, f, _ = broken_meshes()["non-manifold"]
    write_obj(tmp_path / "fin.obj", v, f)
    with pytest.raises(ValueError) as from_file:
        tvf.generate({**SPHERE_SCENE, "domain": {"mesh": str(tmp_path / "fin.obj")}})
    with pytest.raises(ValueError) as from_arrays:
        tvf.generate(SPHERE_SCENE, vertices=v, faces=f)
    file_text = str(from_file.value)
    assert file_text.startswith(str(tmp_path / "fin.obj") + ": ")
    assert file_text[len(str(tmp_path / "fin.obj")):] == str(from_arrays.value)[len("vertices/faces"):]


def test_array_shapes_and_types_are_checked():
    v, f = icosphere(0)
    with pytest.raises(ValueError, match=r"vertices must be a \|V\| x 3 array, not of shape \(12, 2\)"):
        tvf.generate(SPHERE_SCENE, vertices=v[:, :2], faces=f)
    with pytest.raises(ValueError, match="faces must be integers"):
        tvf.generate(SPHERE_SCENE, vertices=v, faces=f.astype(float))
    with pytest.raises(ValueError, match="give both vertices"):
        tvf.generate(SPHERE_SCENE, vertices=v)
    with pytest.raises(ValueError, match="face 0 uses vertex -1"):
        tvf.generate(SPHERE_SCENE, vertices=v, faces=np.vstack([[-1, 1, 2], f]))
    with pytest.raises(ValueError, match="face 0 uses vertex 4294967296"):
        tvf.generate(SPHERE_SCENE, vertices=v, faces=np.vstack([[2 ** 32, 1, 2], f]))


# ---- pictures as numpy arrays ----

def test_planar_pictures_are_the_pixels_the_cli_writes(tmp_path):
    v, f = planar_grid(17)
    scene_dir = tmp_path / "s"
    scene_dir.mkdir()
    write_obj(scene_dir / "grid.obj", v, f)
    (scene_dir / "scene.json").write_text(json.dumps({**GRID_SCENE, "domain": {"mesh": "grid.obj"}}))
    code, text = cli("generate", scene_dir / "scene.json", "-o", tmp_path / "out", "-q", "--no-vtk")
    assert code == 0, text
    code, text = cli("render", "texture", tmp_path / "out", "-o", tmp_path / "frames", "-s", 64, "-q")
    assert code == 0, text
    field = tvf.load(str(tmp_path / "out"))
    pictures = tvf.render_texture(field, 64, frames=[0, 5])
    assert len(pictures) == 2
    for k, p in zip([0, 5], pictures):
        assert p.shape == (64, 64, 3) and p.dtype == np.uint8
        assert np.array_equal(p, read_png(tmp_path / "frames" / f"frame_{k:05d}.png"))
    # Streaks, not a flat picture; and the texture moved between the two.
    assert pictures[1].std() > 20
    assert not np.array_equal(pictures[0], pictures[1])
    # One picture as an int gives one array; all of them with None.
    assert np.array_equal(tvf.render_texture(field, 64, frames=0), pictures[0])
    every = tvf.render_texture(field, 64)
    assert len(every) == 6 and np.array_equal(every[5], pictures[1])


def test_pictures_and_files_at_once_and_progress(tmp_path):
    v, f = planar_grid(9)
    field = tvf.generate(GRID_SCENE, vertices=v, faces=f)
    calls = []
    pictures = tvf.render_texture(field, 32, frames=[1, 3], frames_dir=str(tmp_path / "fr"),
                                  progress=lambda done, total: calls.append((done, total)))
    # Files hold every picture from the first asked for to the last.
    assert sorted(p.name for p in (tmp_path / "fr").iterdir()) == [f"frame_{k:05d}.png" for k in (1, 2, 3)]
    assert np.array_equal(read_png(tmp_path / "fr" / "frame_00003.png"), pictures[1])
    assert calls[-1] == (3, 3)


def test_render_texture_injects_dye(tmp_path):
    """streaklines: dye released at each seed from the first picture, drawn in red (the
    first seed's colour) over the gray texture; a seed outside the domain is a ValueError."""
    v, f = planar_grid(9)
    field = tvf.generate(GRID_SCENE, vertices=v, faces=f)

    def reds(p):
        p = p.astype(int)
        return int(((p[..., 0] > p[..., 1] + 80) & (p[..., 0] > p[..., 2] + 80)).sum())

    assert reds(tvf.render_texture(field, 64, frames=5)) == 0
    assert reds(tvf.render_texture(field, 64, frames=5, streaklines=[[0.3, 0.2]], time_scale=5)) > 10
    with pytest.raises(ValueError, match=r"the dye seed \(3, 0\) is outside the domain"):
        tvf.render_texture(field, 64, frames=5, streaklines=[[3, 0]])
    with pytest.raises(ValueError, match="streaklines seed"):
        tvf.render_texture(field, 64, frames=5, streaklines=[[0.3]])


def test_render_texture_carries_timelines(tmp_path):
    """timelines: segments drawn at the first picture and carried, in light blue over the
    gray texture; malformed or misplaced ones are ValueErrors."""
    v, f = planar_grid(9)
    field = tvf.generate(GRID_SCENE, vertices=v, faces=f)

    def blues(p):
        p = p.astype(int)
        return int(((p[..., 2] > p[..., 0] + 100) & (p[..., 1] > p[..., 0] + 60)).sum())

    assert blues(tvf.render_texture(field, 64, frames=5)) == 0
    assert blues(tvf.render_texture(field, 64, frames=5, timelines=[[[-0.5, 0.1], [0.5, 0.1]]])) > 10
    with pytest.raises(ValueError, match=r"the timeline's last point \(3, 0\) is outside the domain"):
        tvf.render_texture(field, 64, frames=5, timelines=[[[0, 0], [3, 0]]])
    with pytest.raises(ValueError, match="a timeline is two points"):
        tvf.render_texture(field, 64, frames=5, timelines=[[[0, 0]]])


def write_saddle_field(path, n=21, rate=27.0, frames=11):
    """The saddle V = (rate x, -rate y) on an n x n grid over [-1, 1]^2, t in [0, 1], as a
    field file (docs/file_formats.md: vertex iy*n + ix, each cell cut along its diagonal;
    vectors in world x, y): no generator designs a flow this fast."""
    x = np.linspace(-1.0, 1.0, n)
    xx, yy = np.meshgrid(x, x)
    positions = np.stack([xx.ravel(), yy.ravel(), np.zeros(n * n)], axis=1).astype("<f8")
    ix, iy = np.meshgrid(np.arange(n - 1), np.arange(n - 1))
    v00 = (iy * n + ix).ravel()
    faces = np.empty((2 * v00.size, 3), dtype="<i4")
    faces[0::2] = np.stack([v00, v00 + 1, v00 + n + 1], axis=1)
    faces[1::2] = np.stack([v00, v00 + n + 1, v00 + n], axis=1)
    field = np.empty((frames, n * n, 2), dtype="<f8")
    field[:, :, 0] = rate * positions[:, 0]
    field[:, :, 1] = -rate * positions[:, 1]
    header = json.dumps({"vertices": n * n, "faces": int(faces.shape[0]), "frames": frames, "t0": 0.0, "t1": 1.0,
                         "scene": None}).encode()
    header += b" " * ((8 - (20 + len(header)) % 8) % 8)  # arrays 8-byte aligned
    with open(path, "wb") as out:
        out.write(b"TVFFIELD" + struct.pack("<IQ", 1, len(header)) + header)
        out.write(positions.tobytes() + faces.tobytes() + field.tobytes())


def test_render_texture_warns_of_a_timeline_torn_apart(tmp_path):
    """A timeline across a fast saddle's stable separatrix is torn apart by t = 1 (neighbours
    1e-12 apart at the start end further apart than an edge): a RuntimeWarning names it and
    says at how many pictures and why; one that does not cross the separatrix gives none."""
    write_saddle_field(tmp_path / "field.tvff")
    field = tvf.load(str(tmp_path / "field.tvff"))
    with pytest.warns(RuntimeWarning, match=r"timelines\[0\] is not resolved at [0-9]+ of 11 pictures, from t = "
                                            r"[0-9.]+: .*the flow tears it apart"):
        tvf.render_texture(field, 64, frames=[0, 10], pictures=11, timelines=[[[-0.3, 0.6], [0.5, 0.6]]])
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        tvf.render_texture(field, 64, frames=[0, 10], pictures=11, timelines=[[[0.2, 0.5], [0.6, 0.5]]])


def test_render_stops_between_pictures_and_leaves_no_output(tmp_path):
    """progress returning False (tvf.Cancelled) or raising KeyboardInterrupt stops the
    animation before its next picture: no frame folder, no video, no temporaries."""
    v, f = planar_grid(9)
    field = tvf.generate(GRID_SCENE, vertices=v, faces=f)
    total = 2000  # far more pictures than are made before the stop is seen (50 ms polls)
    calls = []

    def stop(done, all_):
        calls.append((done, all_))
        return False

    with pytest.raises(tvf.Cancelled, match="rendering cancelled"):
        tvf.render_texture(field, 64, frames=[0, total - 1], pictures=total,
                           frames_dir=str(tmp_path / "frames"), progress=stop)
    assert calls and calls[-1][1] == total and calls[-1][0] < total
    assert list(tmp_path.iterdir()) == []

    def interrupt(done, all_):
        raise KeyboardInterrupt

    video = shutil.which("ffmpeg") is not None
    with pytest.raises(KeyboardInterrupt):
        tvf.render_texture(field, 64, frames=[0, total - 1], pictures=total, frames_dir=str(tmp_path / "frames"),
                           video=str(tmp_path / "v.mp4") if video else None, progress=interrupt)
    assert list(tmp_path.iterdir()) == []
    # None (or anything but False) lets it finish.
    pictures = tvf.render_texture(field, 32, frames=[0, 2], progress=lambda done, all_: True)
    assert len(pictures) == 2


def test_surface_pictures(tmp_path):
    v, f = icosphere(2)
    field = tvf.generate(SPHERE_SCENE, vertices=v, faces=f)
    pictures = tvf.render_texture(field, 96, frames=[0, 2], view=[0, -1, 0.3])
    assert [p.shape for p in pictures] == [(96, 96, 3), (96, 96, 3)]
    p = pictures[1]
    # White background in the corners, the textured sphere in the middle.
    assert np.all(p[0, 0] == 255) and np.all(p[-1, -1] == 255)
    middle = p[32:64, 32:64].astype(float)
    assert middle.std() > 10 and middle.mean() < 250
    # The same pictures as `tvf render texture` on the written field.
    out = tmp_path / "out"
    d = tvf.Design(SPHERE_SCENE, vertices=v, faces=f)
    d.write_outputs(str(out), vtk=False)
    code, text = cli("render", "texture", out, "-o", tmp_path / "frames", "-s", 96, "--view", "0,-1,0.3", "-q")
    assert code == 0, text
    assert np.array_equal(read_png(tmp_path / "frames" / "frame_00002.png"), p)


def test_bad_render_options_name_the_option():
    v, f = planar_grid(9)
    field = tvf.generate(GRID_SCENE, vertices=v, faces=f)
    with pytest.raises(ValueError, match=r"frame 6 is outside \[0, 5\]"):
        tvf.render_texture(field, 32, frames=[0, 6])
    with pytest.raises(ValueError, match="speed"):
        tvf.render_texture(field, 32, frames=0, speed="fast")
    with pytest.raises(ValueError, match="overlay"):
        tvf.render_texture(field, 32, frames=0, overlay=["arrows"])
    with pytest.raises(ValueError, match="alpha"):
        tvf.render_texture(field, 32, frames=0, alpha=2.0)


# ---- the stub ----

def stub_names():
    tree = ast.parse((Path(tvf.__file__).parent / "__init__.pyi").read_text())
    top, members = set(), {}
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            top.add(node.name)
        if isinstance(node, ast.AnnAssign):
            top.add(node.target.id)
        if isinstance(node, ast.ClassDef):
            members[node.name] = {n.name for n in node.body if isinstance(n, ast.FunctionDef)} | {
                n.target.id for n in node.body if isinstance(n, ast.AnnAssign)}
    return top, members


def test_the_stub_names_every_public_name():
    top, members = stub_names()
    assert set(tvf.__all__) <= top
    public = {n for n in dir(tvf._tvf) if not n.startswith("_")}
    assert public <= top, public - top
    for cls in ("Field", "Design"):
        names = {n for n in dir(getattr(tvf, cls)) if not n.startswith("_")}
        assert names <= members[cls], (cls, names - members[cls])


def test_install_puts_the_stub_beside_the_module(tmp_path):
    build = Path(tvf.__file__).resolve().parents[2]
    if not (build / "cmake_install.cmake").exists():
        pytest.skip("not run from a CMake build tree")
    run = subprocess.run(["cmake", "--install", str(build), "--prefix", str(tmp_path / "p")],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stdout + run.stderr
    installed = list((tmp_path / "p").rglob("tvf/__init__.pyi"))
    assert len(installed) == 1
    package = installed[0].parent
    assert (package / "py.typed").exists() and (package / "__init__.py").exists()
    assert list(package.glob("_tvf*.so"))
    assert (package / "__init__.pyi").read_text() == (Path(tvf.__file__).parent / "__init__.pyi").read_text()
    # The installed package imports and runs.
    code = ("import tvf, numpy as np; v = np.array([[0,0,0],[1,0,0],[0,1,0.]]); "
            "print(tvf.generate({'tvf': 1, 'time': {'frames': 2}, 'elements': [{'kind': 'singular', "
            "'type': 'source', 'path': [[0.3, 0.3, 0, 0]]}]}, vertices=v, faces=[[0, 1, 2]]).vectors.shape)")
    ran = subprocess.run(["/usr/bin/python3" if os.path.exists("/usr/bin/python3") else "python3", "-c", code],
                         capture_output=True, text=True, env={**os.environ, "PYTHONPATH": str(package.parent)})
    assert ran.returncode == 0, ran.stderr
    assert ran.stdout.strip() == "(2, 3, 3)"
