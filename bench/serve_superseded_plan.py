#!/usr/bin/env python3
"""How long a designer's newest change waits behind a solve it made pointless.

For each mesh of libcgal-demo's data archive named on the command line (default: man, cow)
this writes the knot of bench/keyframe_topology_meshes.py (solver.keyframe_topology
"matched": the plan routes and checks paths for seconds before the solve) into a working
folder, starts `tvf serve` on it, waits for the first field, then changes the scene twice
through `PUT /api/scene` (the falloff, +1 each time): the second change comes --wait
seconds after the first, while the first change's solve is planning. It prints one table
row: the first field's solve, the seconds from the second change's PUT to its field being
ready in /api/status, that field's own solve, and their difference: what the user waited
for the superseded solve to stop.

    /usr/bin/python3 bench/serve_superseded_plan.py --tvf build/release/tvf [--wait 4] [MESH ...]
"""
import argparse
import json
import shutil
import socket
import subprocess
import sys
import tarfile
import tempfile
import time
import urllib.request
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from keyframe_topology_meshes import ARCHIVE, knot_scene  # noqa: E402


class Server:
    def __init__(self, tvf, folder):
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            self.port = s.getsockname()[1]
        self.proc = subprocess.Popen([tvf, "serve", "--dir", str(folder), "--port", str(self.port), "-q",
                                      str(folder / "scene.json")], stdout=subprocess.DEVNULL)
        self.base = f"http://127.0.0.1:{self.port}"
        for _ in range(200):
            try:
                self.status()
                return
            except OSError:
                time.sleep(0.1)
        sys.exit(f"{tvf} serve did not answer on port {self.port}")

    def get(self, path):
        with urllib.request.urlopen(self.base + path) as r:
            return json.load(r), r.headers.get("ETag")

    def status(self):
        return self.get("/api/status")[0]

    def put_scene(self, scene, etag):
        req = urllib.request.Request(self.base + "/api/scene", data=json.dumps(scene).encode(), method="PUT",
                                     headers={"Content-Type": "application/json", "If-Match": etag})
        with urllib.request.urlopen(req) as r:
            return r.headers.get("ETag")

    def wait_ready(self, revision, poll=0.02):
        while True:
            st = self.status()
            if st["result_revision"] >= revision and st["state"] == "ready":
                return st
            if st["state"] == "failed":
                sys.exit(f"the solve failed: {st.get('error')}")
            time.sleep(poll)

    def close(self):
        self.proc.terminate()
        self.proc.wait()


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("meshes", nargs="*", default=["man", "cow"])
    ap.add_argument("--tvf", default="build/release/tvf")
    ap.add_argument("--wait", type=float, default=4.0,
                    help="seconds between the first change and the second (the first's solve is under way)")
    args = ap.parse_args()
    tvf = str(Path(args.tvf).resolve())
    print("| mesh | first solve s | newest field after its PUT s | its own solve s | waited for the superseded s |")
    print("|---|---:|---:|---:|---:|")
    for m in args.meshes:
        with tempfile.TemporaryDirectory() as tmp:
            folder = Path(tmp)
            try:
                with tarfile.open(ARCHIVE) as tar:
                    tar.extract(f"data/meshes/{m}.off", folder)
            except (OSError, KeyError) as e:
                sys.exit(f"{ARCHIVE}: {e} (Debian package libcgal-demo)")
            shutil.move(folder / "data/meshes" / f"{m}.off", folder / f"{m}.off")
            scene = knot_scene(folder / f"{m}.off", 0.15, 0.05)
            if scene is None:
                print(f"| {m} | no second point on the flank | | | |")
                continue
            scene["domain"]["mesh"] = f"{m}.off"  # serve reads only inside its folder
            (folder / "scene.json").write_text(json.dumps(scene))
            server = Server(tvf, folder)
            try:
                first = server.wait_ready(1)
                got, etag = server.get("/api/scene")
                current = got["scene"]
                current["falloff"] += 1
                etag = server.put_scene(current, etag)
                time.sleep(args.wait)
                current["falloff"] += 1
                start = time.monotonic()
                etag = server.put_scene(current, etag)
                newest = server.wait_ready(int(etag.strip('"')))
                waited = time.monotonic() - start
                print(f"| {m} | {first['seconds']:.2f} | {waited:.2f} | {newest['seconds']:.2f} | "
                      f"{waited - newest['seconds']:.2f} |")
            finally:
                server.close()


if __name__ == "__main__":
    main()
