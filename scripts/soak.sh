#!/usr/bin/env bash
# Soak test of the closed loop: runs FRAMES frames on the simulated clock (as fast as the machine
# goes), samples the process's resident memory while it runs, then checks the outputs:
#   - resident memory (VmRSS) grows by less than SOAK_RSS_LIMIT_KB (default 1024) from frame
#     min(1000, FRAMES/2) to the last sample taken while frames still run (the samples during
#     the final frame and the teardown, which writes report.json and the pictures, are reported
#     apart: that memory is taken once, at the end);
#   - bus_out.log holds one detection list per frame, frame counters consecutive (python-can reads
#     every line), bus_in.log parses, frames.csv has a line per frame, report.json says complete;
#   - a replay of bus_in.log gives a byte-identical bus_out.log and detections.json
#     (SOAK_REPLAY=0 skips it: it takes as long as the run).
#
# usage: scripts/soak.sh FRAMES [SCENARIO.toml]
#   Without a scenario: the runway scene (builtin "default": runway, four reflector-carrying
#   objects, a moving vehicle) seen from an ownship holding still 4 km short of the threshold at
#   230 m, so that every frame traces and detects the scene (the default approach would fly
#   into the ground after 63 s). The radar is the default one made cheaper where it does not
#   change what the outputs carry (16 pulses, 0.25 m target rays, a 3.5-5 km range gate around
#   the objects): 3 to 6 detections and about 23 bus frames a frame (the default radar: 4 to 7
#   detections), at about half its cost. Pass a scenario to soak another configuration.
# environment: RADAR_EMU (default build/app/radar-emu), SOAK_OUT (default out/soak),
#   SOAK_SAMPLE_S (sampling period, default 1), SOAK_RSS_LIMIT_KB, SOAK_REPLAY,
#   SOAK_CHECK_ONLY=1 (check the outputs of an earlier soak in SOAK_OUT without running again).
# Writes SOAK_OUT/memory.csv (elapsed_s,frame,rss_kb), SOAK_OUT/run/ and SOAK_OUT/replay/ (the
# runs' outputs) and SOAK_OUT/summary.txt. Exit status 0 only when every check passes.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
if [ $# -lt 1 ] || ! [[ "$1" =~ ^[0-9]+$ ]] || [ "$1" -lt 1 ]; then
  echo "usage: scripts/soak.sh FRAMES [SCENARIO.toml]" >&2
  exit 2
fi
frames="$1"
exe="${RADAR_EMU:-$root/build/app/radar-emu}"
out="${SOAK_OUT:-$root/out/soak}"
period="${SOAK_SAMPLE_S:-1}"
limit_kb="${SOAK_RSS_LIMIT_KB:-1024}"
replay="${SOAK_REPLAY:-1}"
check_only="${SOAK_CHECK_ONLY:-0}"
if [ "$check_only" != "1" ] && [ ! -x "$exe" ]; then
  echo "soak: $exe not found: build first (scripts/build.sh)" >&2
  exit 2
fi

# Frame of the last complete line of frames.csv (the writer keeps the file current within
# milliseconds); -1 before the first.
last_frame() {
  [ -f "$out/run/frames.csv" ] || { echo -1; return; }
  # The last line may still be partial: the one before it is complete (one frame behind).
  tail -c 8192 "$out/run/frames.csv" | head -n -1 | tail -n 1 | awk -F, '
    { last = $1 } END { if (last ~ /^[0-9]+$/) print last; else print -1 }'
}

# The run, its memory sampled, then the replay of its input log.
run_and_sample() {
  rm -rf "$out/run" "$out/replay"
  mkdir -p "$out"
  local scenario
  if [ $# -ge 2 ]; then
    scenario="$2"
  else
    scenario="$out/soak_runway.toml"
    cat >"$scenario" <<'EOF'
name = "soak: runway scene, ownship holding 4 km short of the threshold"
[scene]
builtin = "default"
[ownship]
start_enu_m = [0.0, -4000.0, 230.0]
velocity_enu_mps = [0.0, 0.0, 0.0]
[radar]
pulses = 16
target_ray_spacing_m = 0.25
swath_start_m = 3500.0
max_range_m = 5000.0
EOF
  fi
  echo "elapsed_s,frame,rss_kb" >"$out/memory.csv"
  "$exe" run "$scenario" --frames "$frames" --out "$out/run" --quiet &
  local pid=$!
  trap 'kill -INT "$pid" 2>/dev/null || true' INT TERM
  local start rss now rc=0
  start=$(date +%s.%N)
  while kill -0 "$pid" 2>/dev/null; do
    rss=$(awk '/^VmRSS:/ { print $2 }' "/proc/$pid/status" 2>/dev/null || true)
    if [ -n "$rss" ]; then
      now=$(date +%s.%N)
      printf '%s,%s,%s\n' "$(awk -v a="$now" -v b="$start" 'BEGIN { printf "%.1f", a - b }')" \
        "$(last_frame)" "$rss" >>"$out/memory.csv"
    fi
    sleep "$period"
  done
  wait "$pid" || rc=$?
  trap - INT TERM
  if [ "$rc" -ne 0 ]; then
    echo "soak: radar-emu run exited with status $rc" >&2
    exit 1
  fi
  awk -v a="$(date +%s.%N)" -v b="$start" 'BEGIN { printf "%.1f\n", a - b }' >"$out/wall_run_s"
  if [ "$replay" != "0" ]; then
    "$exe" replay "$out/run/bus_in.log" "$scenario" --frames "$frames" --out "$out/replay" --quiet
  fi
}

if [ "$check_only" != "1" ]; then
  run_and_sample "$@"
fi
wall_run=$(cat "$out/wall_run_s" 2>/dev/null || echo 0)

/usr/bin/python3 - "$out" "$frames" "$limit_kb" "$replay" "$wall_run" <<'EOF'
import csv, filecmp, json, sys
import can

out, frames, limit_kb, replay, wall_run = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4] != "0", float(sys.argv[5])
lines, failed = [], False


def check(ok, text):
    global failed
    lines.append(("PASS " if ok else "FAIL ") + text)
    failed |= not ok


# Memory: the first sample at or after the baseline frame against the last one taken while
# frames were still running (the last complete line of frames.csv before frame FRAMES - 2:
# frames.csv is read one line behind). Later samples fall in the last frames
# or the teardown (report.json, timing.png, detections.png): reported, not held to the limit.
samples = [(float(r["elapsed_s"]), int(r["frame"]), int(r["rss_kb"]))
           for r in csv.DictReader(open(f"{out}/memory.csv"))]
base_frame = min(1000, frames // 2)
running = [s for s in samples if base_frame <= s[1] < frames - 2]
if len(running) >= 2:
    b, e = running[0], running[-1]
    grow = e[2] - b[2]
    peak = max(s[2] for s in running)
    check(grow < limit_kb,
          f"resident memory {b[2]} kB at frame {b[1]}, {e[2]} kB at frame {e[1]}: {grow:+d} kB "
          f"(limit {limit_kb} kB); peak in between {peak} kB; {len(samples)} samples")
    end = [s for s in samples if s[1] >= frames - 2]
    if end:
        lines.append(f"INFO teardown (last frame, report.json and the pictures): peak "
                     f"{max(s[2] for s in end)} kB, {max(s[2] for s in end) - e[2]:+d} kB "
                     f"over the running frames, once")
else:
    check(False, f"too few memory samples while frames ran after frame {base_frame} "
                 f"({len(running)}): raise FRAMES or lower SOAK_SAMPLE_S")

rep = json.load(open(f"{out}/run/report.json"))
check(rep["frames"] == frames and not rep["interrupted"],
      f"report.json: {rep['frames']} frames of {frames}, interrupted {rep['interrupted']}")
os_ = rep["output_stream"]
check(os_["complete"] and os_["frames_written"] == frames,
      f"report.json output_stream: complete {os_['complete']}, {os_['frames_written']} frames "
      f"and {os_['bus_frames_written']} bus frames written, {os_['writer_waits']} writer waits")

# Every candump line parses with python-can; one list header per frame, counters consecutive.
headers, n_out = [], 0
for msg in can.CanutilsLogReader(f"{out}/run/bus_out.log"):
    n_out += 1
    if msg.arbitration_id in (0x708, 0x70B):
        headers.append(msg.data[0] | (msg.data[1] << 8))
gaps = sum(1 for a, c in zip(headers, headers[1:]) if c != (a + 1) % 65536)
check(len(headers) == frames and gaps == 0 and (not headers or headers[0] == 0),
      f"bus_out.log: {n_out} frames, {len(headers)} detection lists for {frames} radar frames, "
      f"{gaps} frame-counter gaps")
n_in = sum(1 for _ in can.CanutilsLogReader(f"{out}/run/bus_in.log"))
check(n_in == rep["bus"]["frames_in"],
      f"bus_in.log: {n_in} frames parsed, report.json bus.frames_in {rep['bus']['frames_in']}")
with open(f"{out}/run/frames.csv") as f:
    n_csv = sum(1 for _ in f) - 1
check(n_csv == frames, f"frames.csv: {n_csv} frame lines")
if replay:
    for name in ("bus_out.log", "detections.json"):
        same = filecmp.cmp(f"{out}/run/{name}", f"{out}/replay/{name}", shallow=False)
        check(same, f"replay of bus_in.log: {name} byte-identical: {same}")
st = rep["stage_timing"]["frame"]
lines.append(f"INFO wall {wall_run:.0f} s for {frames} frames; frame p50 {st['p50_ms']:.2f} ms, "
             f"p99 {st['p99_ms']:.2f} ms, max {st['max_ms']:.2f} ms ({st['percentiles']})")
text = "\n".join(lines) + "\n"
open(f"{out}/summary.txt", "w").write(text)
sys.stdout.write(text)
sys.exit(1 if failed else 0)
EOF
