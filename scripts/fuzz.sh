#!/usr/bin/env bash
# Coverage-guided fuzzing of radar-emu's parsers and decoders with libFuzzer (tests/fuzz/README.md).
# Builds a separate clang tree (-DRADAR_EMU_FUZZ=ON: -fsanitize=fuzzer,address,undefined), then
# runs each harness from a working corpus seeded with tests/fuzz/corpus/<name>/ and prints,
# per harness, the executions, executions per second and the outcome.
#
# usage: scripts/fuzz.sh [--time S | --runs N] [--parallel P] [--build DIR] [--report FILE]
#                        [--no-build] [HARNESS...]
#   --time S      run each harness for S seconds (default 600)
#   --runs N      run each harness for N executions instead (the acceptance runs: --runs 10000000)
#   --parallel P  harnesses run at once (default 1; each is one process on one core)
#   --build DIR   the clang build tree (default build-fuzz)
#   --report FILE append the table of results (markdown) to FILE
#   HARNESS       any of: canaerospace icd_classic icd_fd candump modbus_nav modbus_table
#                 scenario_toml gltf obj stl websocket sar_case (default: all)
# A finding (crash, sanitizer report, leak, broken FUZZ_CHECK, timeout, out-of-memory) stops
# that harness, leaves the input in DIR/artifacts/<name>/ and makes the script exit 1. Replay
# one with DIR/tests/fuzz/fuzz_<name> FILE; keep it as a regression test by copying it to
# tests/fuzz/regressions/<name>/ (fuzz_replay_tests runs those in every build).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
all=(canaerospace icd_classic icd_fd candump modbus_nav modbus_table scenario_toml gltf obj stl
     websocket sar_case)
time_s=600
runs=""
parallel=1
build="$root/build-fuzz"
report=""
do_build=1
targets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --time) time_s="$2"; shift 2 ;;
    --runs) runs="$2"; shift 2 ;;
    --parallel) parallel="$2"; shift 2 ;;
    --build) build="$2"; shift 2 ;;
    --report) report="$2"; shift 2 ;;
    --no-build) do_build=0; shift ;;
    -h|--help) sed -n '2,19p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit 0 ;;
    -*) echo "fuzz.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
    *) targets+=("$1"); shift ;;
  esac
done
[ ${#targets[@]} -eq 0 ] && targets=("${all[@]}")
for t in "${targets[@]}"; do
  [[ " ${all[*]} " == *" $t "* ]] || { echo "fuzz.sh: unknown harness '$t' (${all[*]})" >&2; exit 2; }
done

if [ "$do_build" -eq 1 ]; then
  command -v clang++ >/dev/null 2>&1 || { echo "fuzz.sh: clang++ not found (scripts/install-deps.sh installs clang)" >&2; exit 2; }
  launcher=()
  command -v ccache >/dev/null 2>&1 && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  gen=()
  [ ! -f "$build/CMakeCache.txt" ] && command -v ninja >/dev/null 2>&1 && gen=(-G Ninja)
  echo "== build (clang, libFuzzer + ASan + UBSan) in $build =="
  cmake -S "$root" -B "$build" "${gen[@]}" -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
    -DRADAR_EMU_FUZZ=ON -DRADAR_EMU_BUILD_TESTS=OFF -DRADAR_EMU_BUILD_BENCHMARKS=OFF \
    -DCMAKE_BUILD_TYPE=Debug -DRADAR_EMU_LINE_DEBUG_INFO=ON -DRADAR_EMU_FUZZ_OPT=-O1 "${launcher[@]}" \
    >/dev/null
  cmake --build "$build" --target fuzz_all -j "$(nproc)"
fi

export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:allocator_may_return_null=0}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
logs="$build/fuzz-logs"
mkdir -p "$logs"

run_one() {  # run_one NAME -> writes $logs/NAME.log and $logs/NAME.result
  local name="$1"
  local corpus="$build/corpus/$name" artifacts="$build/artifacts/$name"
  mkdir -p "$corpus" "$artifacts"
  cp -n "$root/tests/fuzz/corpus/$name/"* "$corpus/" 2>/dev/null || true
  local limit=(-max_total_time="$time_s")
  [ -n "$runs" ] && limit=(-runs="$runs")
  local start end rc=0
  start=$(date +%s)
  # -timeout: one input taking > 10 s is a finding (a hang); -rss_limit_mb: > 2 GiB is one too.
  # -max_len: frame sequences stay short; a round trip of 255 detections takes 13 kB; scenario
  # and mesh files are larger (16 kB: a few hundred triangles; larger random meshes only slow
  # the mesh check's quadratic T-junction pass, bounded at 5000 open edges, down).
  # websocket: a request head up to the server's 8 kB limit, then frames.
  local max_len=4096
  case "$name" in
    icd_classic|icd_fd|modbus_table|scenario_toml|gltf|obj|stl|websocket|sar_case) max_len=16384 ;;
  esac
  (cd "$artifacts" && "$build/tests/fuzz/fuzz_$name" "${limit[@]}" -timeout=10 -rss_limit_mb=2048 \
      -max_len="$max_len" -print_final_stats=1 -artifact_prefix="$artifacts/" "$corpus" \
      "$root/tests/fuzz/corpus/$name") >"$logs/$name.log" 2>&1 || rc=$?
  end=$(date +%s)
  local execs rate rss
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$logs/$name.log" | tail -1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$logs/$name.log" | tail -1)
  rss=$(sed -n 's/^stat::peak_rss_mb: *//p' "$logs/$name.log" | tail -1)
  local outcome="clean"
  if [ "$rc" -ne 0 ]; then
    outcome="FINDING (exit $rc): $(grep -m1 -E 'ERROR: |SUMMARY: |fuzz invariant broken|==ERROR' "$logs/$name.log" || echo see log)"
  fi
  printf '| %s | %s | %s | %s | %s | %s | %s |\n' "$name" "${execs:-?}" "${rate:-?}" \
    "$((end - start))" "$(ls "$corpus" | wc -l)" "${rss:-?}" "$outcome" >"$logs/$name.result"
  [ "$rc" -eq 0 ]
}

echo "== fuzzing: ${targets[*]} ($( [ -n "$runs" ] && echo "$runs runs" || echo "$time_s s") each, $parallel at once; logs in $logs) =="
status=0
pids=()
names=()
for t in "${targets[@]}"; do
  run_one "$t" &
  pids+=($!)
  names+=("$t")
  while [ "$(jobs -rp | wc -l)" -ge "$parallel" ]; do wait -n || true; done
done
for i in "${!pids[@]}"; do
  wait "${pids[$i]}" || status=1
done

header='| harness | executions | exec/s | seconds | corpus files | peak RSS MB | outcome |
|---|---|---|---|---|---|---|'
table="$header"
for t in "${targets[@]}"; do table+=$'\n'"$(cat "$logs/$t.result")"; done
echo "$table"
if [ -n "$report" ]; then
  { echo; echo "$(date -u +%Y-%m-%dT%H:%MZ) $(uname -m), $(nproc) cores: scripts/fuzz.sh $( [ -n "$runs" ] && echo "--runs $runs" || echo "--time $time_s")"; echo; echo "$table"; } >>"$report"
fi
if [ "$status" -ne 0 ]; then
  echo "fuzz.sh: findings: inputs in $build/artifacts/<name>/, logs in $logs/" >&2
fi
exit "$status"
