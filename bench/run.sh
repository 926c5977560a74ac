#!/usr/bin/env bash
# Runs the benchmarks and prints a Markdown table (docs/benchmarks.md).
# Usage: bench/run.sh [build-dir]   (default build/release; builds tvf_bench first)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build/release}
cmake --build "$build" --target tvf_bench >/dev/null
json=$(mktemp)
"$build/bench/tvf_bench" --benchmark_format=json --benchmark_out="$json" --benchmark_out_format=json \
  --benchmark_repetitions=3 --benchmark_report_aggregates_only=true >/dev/null
build_type=$(grep -m1 '^CMAKE_BUILD_TYPE:' "$build/CMakeCache.txt" | cut -d= -f2)
cpu=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')
/usr/bin/python3 - "$json" "$build_type" "$cpu" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
ctx = d["context"]
print(f"Machine: {sys.argv[3]}, {ctx['num_cpus']} cores; tvf built {sys.argv[2]}; {ctx['date']}")
print()
print("| case | vertices | frames | median time | per frame | iterations | residual |")
print("|---|---:|---:|---:|---:|---:|---:|")
for b in d["benchmarks"]:
    if b.get("aggregate_name") != "median":
        continue
    name = b["run_name"]
    t = b["real_time"]; unit = b["time_unit"]
    v = int(b.get("vertices", 0)); f = int(b.get("frames", 0))
    per = f"{t / f:.3f} {unit}" if f else ""
    it = b.get("cg_iterations"); res = b.get("residual")
    its = f"{int(it)}" if it else ""
    ress = f"{res:.1e}" if res else ""
    print(f"| {name} | {v or ''} | {f or ''} | {t:.1f} {unit} | {per} | {its} | {ress} |")
PY
rm -f "$json"
