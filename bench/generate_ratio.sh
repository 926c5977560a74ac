#!/usr/bin/env bash
# Issue 15's measure, end to end with `tvf generate`: a scene with moving elements against
# its key frames alone, both in the same run, alternated, each pinned to one core (the CPU
# time of one core stands beside the wall time on a loaded machine).
# Usage: bench/generate_ratio.sh [build-dir] [runs] [scene-with-elements] [scene-key-frames-alone]
# (default build/release, 5 runs, bench/scenes/keyframes_moving_vortex_65.json against
# bench/scenes/keyframes_65.json). Prints each scene's median user + system time and wall
# time, and the ratio of the CPU medians. The 20k sphere's pair,
#   bench/generate_ratio.sh build/release 5 bench/scenes/keyframes_moving_vortex_sphere20k.json \
#     bench/scenes/keyframes_sphere20k.json
# names the mesh sphere20k.off: the scenes are run from a copy beside that mesh, written first
# by the build's bench/tvf_sphere_mesh (the benchmarks' make_geodesic_sphere(45)).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build/release}
runs=${2:-5}
moving=${3:-bench/scenes/keyframes_moving_vortex_65.json}
alone=${4:-bench/scenes/keyframes_65.json}
tvf="$build/tvf"
[[ -x "$tvf" ]] || { echo "no $tvf: build the tvf_cli target first" >&2; exit 1; }
pin=()
command -v taskset >/dev/null && pin=(taskset -c 0)
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
declare -A run_as=([$alone]=$alone [$moving]=$moving)
if grep -q '"sphere20k.off"' "$alone" "$moving"; then
  [[ -x "$build/bench/tvf_sphere_mesh" ]] || { echo "no $build/bench/tvf_sphere_mesh: build it first" >&2; exit 1; }
  "$build/bench/tvf_sphere_mesh" "$dir/sphere20k.off"
  cp "$alone" "$dir/alone.json"
  cp "$moving" "$dir/moving.json"
  run_as=([$alone]=$dir/alone.json [$moving]=$dir/moving.json)
fi
for ((i = 0; i < runs; ++i)); do
  for scene in "$alone" "$moving"; do
    /usr/bin/time -f "$scene %U %S %e" -a -o "$dir/times" "${pin[@]}" "$tvf" generate "${run_as[$scene]}" \
      -o "$dir/out" -q 2>/dev/null >/dev/null
  done
done
echo "load average: $(cut -d' ' -f1-3 /proc/loadavg)"
/usr/bin/python3 - "$dir/times" "$alone" "$moving" <<'PY'
import statistics, sys
runs = {}
for line in open(sys.argv[1]):
    scene, user, system, wall = line.split()
    runs.setdefault(scene, []).append((float(user) + float(system), float(wall)))
cpu = {}
for scene in sys.argv[2:]:
    r = runs[scene]
    cpu[scene] = statistics.median(c for c, _ in r)
    print(f"{scene}: CPU {cpu[scene]:.2f} s, wall {statistics.median(w for _, w in r):.2f} s (medians of {len(r)})")
print(f"ratio (CPU): {cpu[sys.argv[3]] / cpu[sys.argv[2]]:.2f}")
PY
