#!/usr/bin/env bash
# Runs the benchmarks and prints a Markdown table (docs/benchmarks.md).
# Usage: bench/run.sh [build-dir] [regex]   (default build/release and every case)
# Each case runs in its own process, so its peak memory (peak_mb) is its own.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build/release}
filter=${2:-.}
cmake --build "$build" --target tvf_bench >/dev/null
bench="$build/bench/tvf_bench"
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
i=0
while read -r name; do
  i=$((i + 1))
  # Cases that fix their own repetitions (the slow ones) keep them.
  reps=3
  [[ "$name" == */repeats:* ]] && reps=1
  base=${name%%/iterations:*}
  "$bench" --benchmark_filter="^${base}(/iterations:[0-9]+)?(/repeats:[0-9]+)?\$" \
    --benchmark_repetitions="$reps" --benchmark_report_aggregates_only=true \
    --benchmark_out="$dir/$i.json" --benchmark_out_format=json >/dev/null 2>"$dir/$i.err" ||
    { cat "$dir/$i.err" >&2; exit 1; }
done < <("$bench" --benchmark_list_tests --benchmark_filter="$filter")
build_type=$(grep -m1 '^CMAKE_BUILD_TYPE:' "$build/CMakeCache.txt" | cut -d= -f2)
cpu=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')
/usr/bin/python3 - "$dir" "$build_type" "$cpu" <<'PY'
import glob, json, os, sys
files = sorted(glob.glob(os.path.join(sys.argv[1], "*.json")), key=lambda f: int(os.path.basename(f)[:-5]))
runs = [json.load(open(f)) for f in files]
ctx = runs[0]["context"] if runs else {"num_cpus": "?", "date": "?"}
print(f"Machine: {sys.argv[3]}, {ctx['num_cpus']} cores; tvf built {sys.argv[2]}; {ctx['date']}")
print()
print("| case | vertices | frames | median time | per frame | CPU, all threads | iterations | residual | peak memory | method |")
print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---|")
shown = {"vertices", "frames", "cg_iterations", "residual", "peak_mb", "cpu_ms"}
for d in runs:
    rows = [b for b in d["benchmarks"] if b.get("aggregate_name") == "median"]
    if not rows:  # a single repetition reports the run itself
        rows = [b for b in d["benchmarks"] if b.get("run_type") == "iteration"]
    for b in rows:
        name = b["run_name"].split("/iterations:")[0]
        t = b["real_time"]; unit = b["time_unit"]
        v = int(b.get("vertices", 0)); f = int(b.get("frames", 0))
        per = f"{t / f:.3f} {unit}" if f else ""
        it = b.get("cg_iterations"); res = b.get("residual"); mem = b.get("peak_mb")
        its = f"{int(it)}" if it else ""
        ress = f"{res:.1e}" if res else ""
        mems = (f"{mem / 1024:.1f} GiB" if mem >= 1024 else f"{mem:.0f} MiB") if mem else ""
        label = b.get("label", "").replace("|", "/")
        # Counters of a case's own (e.g. BM_SparseFactor's CPU times of its phases).
        extra = [f"{k} {b[k]:.1f}" for k in sorted(b) if k.endswith("_ms") and k not in shown]
        if extra:
            label = "; ".join(([label] if label else []) + extra)
        cpu = b.get("cpu_ms"); cpus = f"{cpu:.1f} ms" if cpu else ""
        print(f"| {name} | {v or ''} | {f or ''} | {t:.1f} {unit} | {per} | {cpus} | {its} | {ress} | {mems} | {label} |")
PY
