"""The Python module tvf (DESIGN §12): the same numbers as the command line's files,
errors as ValueError with the command line's sentence, the stateful Design, progress and
cancellation, integral curves, and the animation exports read back by their own readers.

Run by ctest (tests/CMakeLists.txt sets PYTHONPATH to BUILD/python and TVF_CLI to the
tvf program); small scenes (17x17 grids, 5 frames) keep it to seconds."""
import copy
import json
import os
import subprocess
import threading

import numpy as np
import pytest

import tvf

TVF = os.environ.get("TVF_CLI", "tvf")

SCENE = {
    "tvf": 1,
    "domain": {"grid": {"size": [17, 17], "min": [-1, -1], "max": [1, 1]}},
    "time": {"frames": 5, "range": [0, 1]},
    "generator": "constrained",
    "elements": [
        {"kind": "singular", "type": "source", "path": [[-0.4, -0.3, 0], [-0.2, -0.3, 1]]},
        {"kind": "singular", "type": "ccw_center", "path": [[0.4, 0.4, 0]]},
    ],
}


def cli(*args):
    run = subprocess.run([TVF, *map(str, args)], capture_output=True, text=True)
    return run.returncode, run.stdout + run.stderr


@pytest.fixture()
def scene_file(tmp_path):
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(SCENE))
    return path


@pytest.fixture()
def generated(tmp_path, scene_file):
    out = tmp_path / "out"
    code, text = cli("generate", scene_file, "-o", out, "-q", "--no-vtk")
    assert code == 0, text
    return out


def test_generate_gives_the_numbers_of_field_npy(scene_file, generated):
    f = tvf.generate(str(scene_file))
    assert f.vectors.shape == (5, 17 * 17, 3)
    assert f.vectors.dtype == np.float32
    assert np.array_equal(f.vectors, np.load(generated / "field.npy"))
    assert np.array_equal(f.vertices, np.load(generated / "vertices.npy"))
    assert np.array_equal(f.faces, np.load(generated / "faces.npy"))
    assert np.array_equal(f.times, np.load(generated / "times.npy"))
    # A dict gives the same field as the file.
    assert np.array_equal(tvf.generate(SCENE).vectors, f.vectors)
    # The complex local form: vectors = Re z e1 + Im z e2 (rounded to float32).
    world = f.values.real[..., None] * f.e1[None] + f.values.imag[..., None] * f.e2[None]
    assert np.array_equal(world.astype(np.float32), f.vectors)
    assert not f.values.flags.writeable and f.values.base is not None  # a view, not a copy
    # A generated folder reads back exactly.
    assert np.array_equal(tvf.load(str(generated)).values, f.values)


def test_analyze_gives_the_json_of_tvf_analyze(tmp_path, generated):
    code, text = cli("analyze", generated, "-o", tmp_path / "a.json", "-q", "--no-plots")
    assert code == 0, text
    expected = json.loads((tmp_path / "a.json").read_text())
    got = tvf.analyze(tvf.load(str(generated)))
    assert got == expected
    assert got["frames"] == 5
    assert {s["type"] for s in got["singularities"]} >= {"source"}


def test_bad_input_raises_value_error_with_the_cli_sentence(tmp_path):
    bad = copy.deepcopy(SCENE)
    bad["elements"][0]["type"] = "sourse"
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(bad))
    code, text = cli("generate", path, "-o", tmp_path / "x")
    assert code == 1
    with pytest.raises(ValueError) as e:
        tvf.generate(str(path))
    assert text.strip() == "tvf: error: " + str(e.value)
    assert "elements[0].type" in str(e.value)
    # The place as attributes: the file, the JSON path, and the line and column of the
    # value in the file (json.dumps writes one line; columns count from 1).
    assert e.value.file == str(path)
    assert e.value.json_path == "elements[0].type"
    assert (e.value.line, e.value.column) == (1, path.read_text().index('"sourse"') + 1)
    with pytest.raises(ValueError, match=r"^scene: elements\[0\]\.type") as d:
        tvf.generate(bad)
    assert (d.value.file, d.value.json_path, d.value.line) == ("scene", "elements[0].type", 0)
    with pytest.raises(TypeError):
        tvf.generate(42)


def test_design_edits_undoes_and_redoes():
    d = tvf.Design(SCENE)
    before = d.generate().vectors.copy()
    assert d.scene["edits"] == []
    report = d.edit(op="smooth", strength=0.5)
    assert report["summary"]
    assert [e["op"] for e in d.scene["edits"]] == ["smooth"]
    edited = d.field.vectors
    assert not np.array_equal(edited, before)
    # The edited scene regenerates the edited field (edits replay from the scene).
    assert np.array_equal(tvf.generate(d.scene).vectors, edited)
    d.undo()
    assert d.scene["edits"] == [] and d.can_redo
    assert np.array_equal(d.field.vectors, before)
    d.redo()
    assert len(d.scene["edits"]) == 1
    # A refused edit changes nothing and says why.
    with pytest.raises(ValueError, match="refused to cancel.*the scene is unchanged"):
        d.edit({"op": "cancel", "frame": 2, "pair": [[-0.3, -0.3], [0.4, 0.4]]})
    assert len(d.scene["edits"]) == 1
    # Assigning a scene is validated and undoable.
    moved = d.scene
    moved["elements"][1]["path"] = [[0.2, 0.5, 0]]
    d.scene = moved
    assert not d.has_field
    assert d.analyze()["frames"] == 5
    d.undo()
    assert d.scene["elements"][1]["path"] == [[0.4, 0.4, 0.0]]
    with pytest.raises(ValueError, match=r"elements\[1\]\.path"):
        d.scene = {**moved, "elements": [moved["elements"][0], {**moved["elements"][1], "path": []}]}


def test_progress_and_cancellation():
    calls = []
    f = tvf.generate(SCENE, progress=lambda done, total: calls.append((done, total)))
    assert f.frames == 5
    assert calls and calls[-1] == (5, 5)
    stop = threading.Event()
    stop.set()
    d = tvf.Design({**SCENE, "generator": "spacetime"})
    with pytest.raises(tvf.Cancelled):
        d.generate(cancel=stop)
    assert not d.has_field

    def interrupt(done, total):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        d.generate(progress=interrupt)
    assert d.generate().frames == 5  # still usable


def test_streamline_and_pathline_of_a_radial_field():
    one_source = {**SCENE, "generator": "basis",
                  "elements": [{"kind": "singular", "type": "source", "path": [[0, 0, 0]]}]}
    f = tvf.generate(one_source)
    s = f.streamline([0.5, 0.0], 0.0)
    assert s["points"].shape[1] == 3 and len(s["points"]) > 3
    assert np.abs(s["points"][:, 1]).max() < 1e-9  # a source's streamlines are rays
    assert s["stop_forward"] == "boundary"
    p = f.pathline([0.25, 0.0], 0.0, 0.5)
    assert np.all(np.diff(p["times"]) > 0) and p["times"][0] == 0.0
    assert np.all(np.diff(p["points"][:, 0]) > 0)  # moving away from the source


def test_ftle_streakline_and_timeline_give_the_command_lines_numbers(tmp_path, generated):
    f = tvf.load(str(generated))
    r = f.ftle(0.5)
    code, text = cli("ftle", generated, "--horizon", 0.5, "-o", tmp_path / "ftle", "-q", "--pictures", 0,
                     "--no-vtk")
    assert code == 0, text
    for direction in ("forward", "backward"):
        assert r[direction].shape == (5, 17 * 17) and r[direction].dtype == np.float32
        assert np.array_equal(r[direction], np.load(tmp_path / "ftle" / f"ftle_{direction}.npy"), equal_nan=True)
    assert r["forward_cut"] == 2 and r["forward_span"][0] == 0.5  # the windows from 0.75 and 1 reach past 1
    assert np.isfinite(r["forward"][0]).sum() > 0
    only = f.ftle(0.5, direction="backward", frames=[4])
    assert only["forward"] is None and np.isnan(only["backward"][:4]).all()
    assert np.array_equal(only["backward"][4], r["backward"][4], equal_nan=True)

    s = f.streakline([-0.6, -0.3], 0.0, 0.5)
    code, text = cli("streaklines", generated, "--seed", -0.6, -0.3, "--from", 0, "--to", 0.5, "-o",
                     tmp_path / "s.json", "-q", "--no-picture")
    assert code == 0, text
    j = json.loads((tmp_path / "s.json").read_text())
    assert np.array_equal(s["points"], np.array(j["points"])[:, :3])
    assert np.array_equal(s["release"], np.array(j["points"])[:, 3])
    assert s["t"] == 0.5 and s["released"] == j["released"] and s["left"] == j["left"]
    assert all(s[k] == j[k] for k in ("resolution", "largest_gap", "unresolved", "unresolved_by"))
    assert np.all(np.diff(s["release"]) > 0)  # oldest first

    tl = f.timeline([-0.5, 0.0], [0.5, 0.0], 0.0, 1.0)
    code, text = cli("timelines", generated, "--line", -0.5, 0, 0.5, 0, "--from", 0, "--to", 1, "-o",
                     tmp_path / "t.json", "-q", "--no-picture")
    assert code == 0, text
    j = json.loads((tmp_path / "t.json").read_text())
    assert np.array_equal(tl["points"], np.array(j["points"])[:, :3])
    assert tl["parameter"][0] == 0.0 and tl["parameter"][-1] == 1.0
    assert all(tl[k] == j[k] for k in ("resolution", "largest_gap", "unresolved", "unresolved_by"))
    gaps = np.linalg.norm(np.diff(tl["points"], axis=0), axis=1)
    assert tl["unresolved"] == np.count_nonzero(gaps > tl["resolution"]) and tl["largest_gap"] == gaps.max()
    coarse = f.timeline([-0.5, 0.0], [0.5, 0.0], 0.0, 1.0, count=2, max_gap=10.0)
    assert len(coarse["points"]) == 2 and coarse["resolution"] == 10.0
    assert coarse["unresolved_by"] is None
    # Neighbours asked to be 1e-9 apart: the 20,000 particles fall short, and it says which limit.
    fine = f.timeline([-0.5, 0.0], [0.5, 0.0], 0.0, 1.0, max_gap=1e-9)
    assert fine["unresolved"] > 0 and fine["unresolved_by"] == "particles" and len(fine["points"]) == 20000

    # Progress after each frame and direction; a set cancel stops it (tvf.Cancelled).
    calls = []
    f.ftle(0.5, progress=lambda done, total: calls.append((done, total)))
    assert calls and calls[-1] == (10, 10)
    stop = threading.Event()
    stop.set()
    with pytest.raises(tvf.Cancelled, match="analysis cancelled"):
        f.ftle(0.5, cancel=stop)

    with pytest.raises(ValueError, match="give a horizon of at least"):
        f.ftle(1e-300)
    with pytest.raises(ValueError, match="direction"):
        f.ftle(0.5, direction="sideways")
    with pytest.raises(ValueError, match="outside the domain"):
        f.streakline([3.0, 0.0])
    with pytest.raises(ValueError, match="are one point of the domain"):
        f.timeline([0.2, 0.2], [0.2, 0.2])


def test_a_streakline_of_a_steady_field_is_its_streamline():
    # A source that stays put: dye released on the x axis stays on it (the streamline through
    # the seed is the ray), oldest furthest out.
    one_source = {**SCENE, "generator": "basis",
                  "elements": [{"kind": "singular", "type": "source", "path": [[0, 0, 0]]}]}
    f = tvf.generate(one_source)
    s = f.streakline([0.25, 0.0], 0.0, 0.5)
    line = f.streamline([0.25, 0.0], 0.0)
    assert np.abs(s["points"][:, 1]).max() < 1e-9 and np.abs(line["points"][:, 1]).max() < 1e-9
    assert np.all(np.diff(s["points"][:, 0]) < 0) and s["points"][-1, 0] == 0.25
    assert s["points"][0, 0] <= line["points"][:, 0].max() + 1e-12


def read_ply(path):
    data = path.read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode().splitlines()
    nv = int(next(l for l in header if l.startswith("element vertex")).split()[-1])
    nf = int(next(l for l in header if l.startswith("element face")).split()[-1])
    vertex = np.dtype([(n, "<f4") for n in ("x", "y", "z", "vx", "vy", "vz")])
    v = np.frombuffer(data, vertex, nv, end)
    face = np.dtype([("n", "u1"), ("i", "<i4", 3)])
    f = np.frombuffer(data, face, nf, end + nv * vertex.itemsize)
    assert np.all(f["n"] == 3)
    return header, v, f["i"]


def test_ply_export_holds_the_vectors(tmp_path, generated):
    vectors = np.load(generated / "field.npy")
    code, text = cli("export", generated, "--ply", "-o", tmp_path / "ply", "-q")
    assert code == 0, text
    files = sorted((tmp_path / "ply").iterdir())
    assert [p.name for p in files] == [f"velocity_{j:04d}.ply" for j in range(5)]
    header, v, faces = read_ply(files[3])
    assert "comment t 0.75" in header
    assert np.array_equal(np.stack([v["vx"], v["vy"], v["vz"]], axis=1), vectors[3])
    assert np.array_equal(faces, np.load(generated / "faces.npy"))
    # Python writes the same files.
    written = tvf.load(str(generated)).export_ply(str(tmp_path / "ply2"))
    assert len(written) == 5
    assert (tmp_path / "ply2" / "velocity_0003.ply").read_bytes() == files[3].read_bytes()


def test_vdb_export_reads_back_with_openvdb(tmp_path, generated):
    if not tvf.vdb_available:
        pytest.skip("this tvf was built without OpenVDB (libopenvdb-dev)")
    vdb = pytest.importorskip("pyopenvdb", reason="Debian's python3-openvdb reads the files back")
    vectors = np.load(generated / "field.npy")
    code, text = cli("export", generated, "--vdb", "-o", tmp_path / "vdb", "-q")
    assert code == 0, text
    files = sorted((tmp_path / "vdb").iterdir())
    assert [p.name for p in files] == [f"velocity_{j:04d}.vdb" for j in range(5)]
    h = 2.0 / 16
    for j, path in enumerate(files):
        grid = vdb.read(str(path), "v")
        assert grid.name == "v"
        assert grid.activeVoxelCount() == 17 * 17
        assert grid.transform.voxelSize()[0] == pytest.approx(h)
        assert grid.transform.indexToWorld((3, 5, 0)) == pytest.approx((-1 + 3 * h, -1 + 5 * h, 0))
        assert grid["time"] == pytest.approx(j / 4)
        a = np.zeros((17, 17, 1, 3), np.float32)
        grid.copyToArray(a, ijk=(0, 0, 0))
        # voxel (ix, iy, 0) holds vertex iy*17 + ix
        expected = vectors[j].reshape(17, 17, 3).transpose(1, 0, 2)
        assert np.array_equal(a[:, :, 0, :], expected)
    # Python writes the same grids.
    tvf.export_vdb(tvf.load(str(generated)), str(tmp_path / "vdb2"))
    again = np.zeros((17, 17, 1, 3), np.float32)
    vdb.read(str(tmp_path / "vdb2" / "velocity_0002.vdb"), "v").copyToArray(again, ijk=(0, 0, 0))
    assert np.array_equal(again[:, :, 0, :], vectors[2].reshape(17, 17, 3).transpose(1, 0, 2))


def test_vdb_export_refuses_surfaces(tmp_path):
    sphere = {"tvf": 1, "domain": {"sphere": {"subdivisions": 1}}, "time": {"frames": 2},
              "elements": [{"kind": "singular", "type": "source", "path": [[0, 0, 1, 0]]}]}
    f = tvf.generate(sphere)
    assert not f.planar
    with pytest.raises(ValueError, match="not a planar grid"):
        f.export_vdb(str(tmp_path / "v"))
    assert not (tmp_path / "v").exists() or not any((tmp_path / "v").iterdir())
    assert len(f.export_ply(str(tmp_path / "p"))) == 2


def test_the_report_has_the_key_frame_intervals_of_keyframe_topology_json(tmp_path):
    """With solver.keyframe_topology "matched" the generation's report carries the plan per
    interval, as the generated folder's keyframe_topology.json has it (issue 20)."""
    scene = {
        "tvf": 1,
        "domain": {"grid": {"size": [17, 17], "min": [-1, -1], "max": [1, 1]}},
        "time": {"frames": 9, "range": [0, 1]},
        "generator": "spacetime",
        "solver": {"region_radius": 0.2, "keyframe_topology": "matched",
                   "links": [{"from": [0, 0], "to": [1, 0]}]},
        "keyframes": [
            {"t": 0, "elements": [{"kind": "singular", "type": "source", "at": [-0.5, 0]}]},
            {"t": 1, "elements": [{"kind": "singular", "type": "source", "at": [0.5, 0]}]},
        ],
    }
    stages = []
    report = tvf.generate(scene, stage=stages.append).report
    # What the solve did before its frames' count started, as the command line's progress
    # line says it (the newest within the 50 ms the calling thread looks, so at least the last).
    assert stages and stages[-1] == "planning the topology between key frames (interval 1 of 1)"
    assert "keyframe_intervals" in tvf.Design(scene).generate(stage=stages.append).report
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(scene))
    code, text = cli("generate", path, "-o", tmp_path / "out", "-q", "--no-vtk")
    assert code == 0, text
    written = json.loads((tmp_path / "out" / "keyframe_topology.json").read_text())
    assert report["keyframe_intervals"] == written["intervals"]
    assert report["keyframe_intervals"][0]["matched"][0]["linked"] is True
    assert "keyframe_intervals" not in tvf.generate(SCENE).report
