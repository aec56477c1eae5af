#!/usr/bin/env bash
# Speed-up of `mpirun -np 2 radar-emu rcs` over one process, side by side in one run
# (docs/performance.md, "MPI scale-out"). Rounds interleave the variants so that the load of a
# shared machine falls on all of them alike; prints each run's wall and CPU time, the medians,
# and checks that every CSV is byte-identical to the first one-process run.
#   one process        radar-emu rcs ...             (TBB: every core)
#   one core           taskset -c 0 radar-emu rcs ... (TBB: one thread; what each rank gets)
#   2 ranks            mpirun -np 2 radar-emu rcs ... (bound one core each: one TBB thread each)
# Usage: scripts/bench-mpi.sh [BUILD_DIR] [ROUNDS] [PHI_SWEEP]  (defaults: build 3 0:360:73)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${1:-$root/build}"
rounds="${2:-3}"
phi="${3:-0:360:73}"
exe="$build/app/radar-emu"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1  # CI runs as root

"$exe" scene target vehicle --out "$work/vehicle.glb"
args=(rcs --mesh "$work/vehicle.glb" --freq-hz 10e9 --theta-deg 80 --phi-deg "$phi" --pol VV -q)
echo "command: radar-emu ${args[*]/$work\//} --out X.csv; $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"

declare -A wall cpu
run() {  # NAME COMMAND...: wall and CPU (user + sys, children included) seconds
  local name="$1" out="$work/$1_$round.csv"
  shift
  local t
  t="$( { /usr/bin/time -f '%e %U %S' "$@" "${args[@]}" --out "$out" 2>&1 >/dev/null; } | tail -1)"
  read -r w u s <<<"$t"
  wall[$name]+="$w "
  local c
  c="$(awk -v u="$u" -v s="$s" 'BEGIN {print u + s}')"
  cpu[$name]+="$c "
  printf '  round %d  %-12s wall %6.2f s  cpu %6.2f s\n' "$round" "$name" "$w" "$c"
  if ! cmp -s "$out" "$work/one_1.csv"; then
    echo "bench-mpi: $name round $round: CSV differs from one process" >&2
    exit 1
  fi
}
median() { tr ' ' '\n' | grep . | sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }

for round in $(seq 1 "$rounds"); do
  run one "$exe"
  run one_core taskset -c 0 "$exe"
  run two_ranks mpirun -np 2 "$exe"
done
echo "medians over $rounds rounds (wall / cpu, s):"
for n in one one_core two_ranks; do
  printf '  %-12s %6.2f / %6.2f\n' "$n" "$(echo "${wall[$n]}" | median)" "$(echo "${cpu[$n]}" | median)"
done
w1="$(echo "${wall[one]}" | median)"; w1c="$(echo "${wall[one_core]}" | median)"
w2="$(echo "${wall[two_ranks]}" | median)"
awk -v a="$w1" -v b="$w1c" -v c="$w2" \
  'BEGIN {printf "speed-up of 2 ranks (median wall): %.2f over one process, %.2f over one core\n", a / c, b / c}'
