#!/usr/bin/env bash
# Issue 15's measure, end to end with `tvf generate`: a scene with moving elements against
# its key frames alone, both in the same run, alternated, each pinned to one core (the CPU
# time of one core stands beside the wall time on a loaded machine).
# Usage: bench/generate_ratio.sh [build-dir] [runs] [scene-with-elements] [scene-key-frames-alone]
# (default build/release, 5 runs, bench/scenes/keyframes_moving_vortex_65.json against
# bench/scenes/keyframes_65.json). Prints each scene's median user + system time and wall
# time, and the ratio of the CPU medians.
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
for ((i = 0; i < runs; ++i)); do
  for scene in "$alone" "$moving"; do
    /usr/bin/time -f "$scene %U %S %e" -a -o "$dir/times" "${pin[@]}" "$tvf" generate "$scene" -o "$dir/out" -q \
      2>/dev/null >/dev/null
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
