#!/usr/bin/env bash
# Fuzzes tvf's readers with libFuzzer (docs/architecture.md, "Fuzzing").
# Usage: scripts/fuzz.sh SECONDS [TARGET...]
#   SECONDS  the whole run's budget, shared equally by the targets
#   TARGET   scene mesh_obj mesh_ply mesh_off field session (default: all but session, whose
#            build links the whole library; name it to fuzz it)
# TVF_FUZZ_SEED=N fixes libFuzzer's random seed, so that a run (CI's) explores the same
# inputs each time and a finding is reproducible; unset, each run starts elsewhere.
# TVF_FUZZ_RUNS=N stops each target after N inputs (with a fixed seed the run is then the
# same on any machine, however fast; SECONDS still bounds it).
# Builds the fuzz preset (clang, ASan + UBSan), runs each target from its seed corpus
# (fuzz/corpus/<target>, the example scenes for `scene`) at low priority, keeps what it
# finds in build/fuzz/corpus/<target>, and copies every crashing input to
# fuzz/crashers/<target>/ (replayed by tests/fuzz/replay_test.cpp). Exits 1 when an input
# crashed a target.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
seconds=${1:?usage: scripts/fuzz.sh SECONDS [TARGET...]}
shift
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(scene mesh_obj mesh_ply mesh_off field)
per=$(( seconds / ${#targets[@]} ))
[ "$per" -ge 1 ] || per=1

cmake --preset fuzz >/dev/null
build=()
for t in "${targets[@]}"; do build+=("fuzz_$t"); done
nice -n 19 cmake --build build/fuzz --target "${build[@]}"

found=0
for t in "${targets[@]}"; do
  corpus=build/fuzz/corpus/$t
  artifacts=build/fuzz/artifacts/$t
  mkdir -p "$corpus" "$artifacts"
  rm -f "$artifacts"/*  # only this run's findings are reported
  seeds=(fuzz/corpus/$t)
  dict=()
  case $t in
    scene) seeds+=(examples/*/scene.json); dict=(-dict=fuzz/json.dict) ;;
    session)
      dict=(-dict=fuzz/json.dict)
      # The session's working folder in memory: on a disk, the fsync of every scene save
      # held the target to about one input a second.
      if [ -z "${TMPDIR:-}" ] && [ -d /dev/shm ] && [ -w /dev/shm ]; then export TMPDIR=/dev/shm; fi ;;
    mesh_*) dict=(-dict=fuzz/mesh.dict) ;;
  esac
  # The seeds join the working corpus (a folder, as libFuzzer wants).
  for s in "${seeds[@]}"; do
    if [ -d "$s" ]; then cp -n "$s"/* "$corpus"/ 2>/dev/null || true; else cp -n "$s" "$corpus/seed-$(echo "$s" | tr / _)"; fi
  done
  echo "fuzz: $t for ${per}s"
  status=0
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    nice -n 19 "build/fuzz/fuzz/fuzz_$t" "${dict[@]}" ${TVF_FUZZ_SEED:+-seed=$TVF_FUZZ_SEED} ${TVF_FUZZ_RUNS:+-runs=$TVF_FUZZ_RUNS} -max_total_time="$per" -timeout=20 -rss_limit_mb=4096 \
    -max_len=65536 -print_final_stats=1 -artifact_prefix="$artifacts/" "$corpus" 2>&1 | tail -n 25 || status=$?
  for a in "$artifacts"/crash-* "$artifacts"/leak-* "$artifacts"/timeout-* "$artifacts"/oom-*; do
    [ -e "$a" ] || continue
    mkdir -p "fuzz/crashers/$t"
    cp "$a" "fuzz/crashers/$t/"
    echo "fuzz: $t: $(basename "$a") kept in fuzz/crashers/$t/ (replay: build/fuzz/fuzz/fuzz_$t $a)"
    found=1
  done
  [ "$status" -eq 0 ] || found=1
done
[ "$found" -eq 0 ] || { echo "fuzz: inputs crashed a target (see above)"; exit 1; }
echo "fuzz: no crash in ${seconds}s"
