#!/usr/bin/env bash
# The distributed space-time solve (issue 19; docs/benchmarks.md, "Distributed"): `tvf
# generate` on an N × N grid × 100 frames (two key frames and a vortex moving diagonally
# between them, across the partition, held at every frame) by one process, by
# `mpirun -n 1` and by `mpirun -n 2`; prints Markdown rows: generation time, CG
# iterations, wall and CPU time, peak memory of every rank (/usr/bin/time), the halo, and
# the largest difference from the first run's field (relative to its largest vector).
# Usage: bench/run_mpi.sh [build-dir] [N ...]   (default build/release, N = 141 317 707 1000;
#        RUNS="one;mpirun -n 2" picks the runs, default one, mpirun -n 1 and mpirun -n 2; the
#        first is the reference; FREE_CHECK=1 prints the available memory before each run;
#        KEYFRAMES=0: no key frames, the same two singularities held fixed at every frame
#        instead, beside the moving vortex; PETSC_OPTIONS reaches the ranks as usual;
#        KEEP=DIR: the runs' outputs and logs kept in DIR/N/ instead of a removed temporary
#        folder; REFERENCE=FILE: the differences taken from that field.tvff (a run kept
#        earlier) instead of the first run's — for sizes whose runs do not fit in memory at
#        once or in one session)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build/release}
shift || true
sizes=("$@")
[ ${#sizes[@]} -eq 0 ] && sizes=(141 317 707 1000)
tvf="$build/tvf"
[ -x "$tvf" ] || { echo "run_mpi.sh: $tvf is missing (cmake --build $build --target tvf_cli)" >&2; exit 1; }
mpirun=(mpirun --oversubscribe --allow-run-as-root --bind-to none)
if [ -n "${KEEP:-}" ]; then
  mkdir -p "$KEEP"
  dir=$(cd "$KEEP" && pwd)
else
  dir=$(mktemp -d)
  trap 'rm -rf "$dir"' EXIT
fi
cpu=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')
echo "Machine: $cpu, $(nproc) cores, $(free -g | awk '/Mem:/ {print $2}') GiB; $(date -u +%Y-%m-%d)"
echo
echo "Load average at the start: $(cut -d' ' -f1-3 /proc/loadavg)"
echo
echo "| grid | vertices | frames | run | generation | wall | CPU (all ranks) | iterations | peak RSS per rank | halo | max difference from the first run |"
echo "|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|"
top=$dir
for n in "${sizes[@]}"; do
  dir=$top
  if [ -n "${KEEP:-}" ]; then dir=$top/$n; mkdir -p "$dir"; fi
  cat >"$dir/scene.json" <<EOF
{"tvf": 1,
 "domain": {"grid": {"size": [$n, $n], "min": [-1, -1], "max": [1, 1]}},
 "time": {"frames": 100, "range": [0, 1]},
 "generator": "spacetime",
 "solver": {"region_radius": 0.1},
 "falloff": 40,
$(if [ "${KEYFRAMES:-1}" = 0 ]; then cat <<'KF'
 "elements": [{"kind": "singular", "type": "saddle", "path": [[-0.25, 0, 0]]},
              {"kind": "singular", "type": "source", "path": [[0.25, 0, 0]]},
              {"kind": "singular", "type": "ccw_center", "path": [[-0.7, -0.6, 0], [0.7, 0.6, 1]]}]}
KF
else cat <<'KF'
 "keyframes": [{"t": 0, "elements": [{"kind": "singular", "type": "saddle", "at": [-0.25, 0]},
                                     {"kind": "singular", "type": "source", "at": [0.25, 0]}]},
               {"t": 1, "elements": [{"kind": "singular", "type": "source", "at": [0, 0.5]}]}],
 "elements": [{"kind": "singular", "type": "ccw_center", "path": [[-0.7, -0.6, 0], [0.7, 0.6, 1]]}]}
KF
fi)
EOF
  IFS=';' read -r -a runs <<<"${RUNS:-one;mpirun -n 1;mpirun -n 2}"
  for run in "${runs[@]}"; do
    out="$dir/${run// /_}"
    rm -rf "$out"
    [ -n "${FREE_CHECK:-}" ] && free -g | awk '/Mem:/ {print "free before " r ": " $7 " GiB available"}' r="$run" >&2
    case "$run" in
      one) cmd=(/usr/bin/time -f "peak %M cpu %U %S wall %e" "$tvf") ;;
      *) cmd=("${mpirun[@]}" -n "${run##* }" /usr/bin/time -f "peak %M cpu %U %S wall %e" "$tvf") ;;
    esac
    "${cmd[@]}" generate "$dir/scene.json" -o "$out" --no-vtk >"$out.log" 2>&1 || { cat "$out.log" >&2; exit 1; }
  done
  # The rows, each field compared with the first run's (the reference).
  REFERENCE=${REFERENCE:-} /usr/bin/python3 - "$dir" "$n" "${runs[@]}" <<'PY'
import json, os, re, struct, sys
import numpy as np
folder, n, runs = sys.argv[1], sys.argv[2], sys.argv[3:]
def field(path):  # field.tvff's values (docs/file_formats.md), mapped
    with open(path, "rb") as f:
        f.read(12)
        (h,) = struct.unpack("<Q", f.read(8))
        head = json.loads(f.read(h))
    v, fc, nf = head["vertices"], head["faces"], head["frames"]
    return np.memmap(path, dtype="<f8", mode="r", offset=20 + h + v * 24 + fc * 12, shape=(nf, v, 2))
def name(run): return f"{folder}/{run.replace(' ', '_')}"
ref = field(os.environ.get("REFERENCE") or name(runs[0]) + "/field.tvff")
largest = max(np.hypot(*ref[j].T).max() for j in range(ref.shape[0]))
for run in runs:
    log = open(name(run) + ".log").read()
    gen = re.search(r"generated (\d+) frames × (\d+) vertices by (.*) in ([0-9.]+) s", log)
    its = re.search(r"(\d+) iterations, \d+ ranks?,", gen.group(3))  # the outer CG's
    print(f"{n}², {run}: {gen.group(3)}", file=sys.stderr)
    halo = re.search(r"halo (\d+) vertices", gen.group(3))
    ranks = [(int(p), float(u) + float(s), float(w))
             for p, u, s, w in re.findall(r"peak (\d+) cpu ([0-9.]+) ([0-9.]+) wall ([0-9.]+)", log)]
    peaks = " / ".join(f"{p / 1024 / 1024:.2f}" for p, _, _ in ranks)
    wall = max(w for _, _, w in ranks)
    cpu = sum(c for _, c, _ in ranks)
    b = field(name(run) + "/field.tvff")
    diff = max(np.hypot(*(ref[j] - b[j]).T).max() for j in range(ref.shape[0]))
    print(f"| {n}² | {gen.group(2)} | {gen.group(1)} | {run} | {float(gen.group(4)):.1f} s | {wall:.0f} s | "
          f"{cpu:.0f} s | {its.group(1) if its else ''} | {peaks} GiB | {halo.group(1) if halo else ''} | "
          f"{diff / largest:.1e} |")
PY
  [ -n "${KEEP:-}" ] || rm -rf "$dir"/one "$dir"/mpirun_* "$dir"/*.log
done
