#!/usr/bin/env bash
# Proves that a change which should not change behaviour (a restructuring of the code) leaves every
# output of the radar-emu CLI byte-identical: record every case with the old binary and with the
# new one, then compare the two trees.
#
#   scripts/compare-outputs.sh record BINARY OUTDIR   # runs every case, writes OUTDIR/<case>/
#   scripts/compare-outputs.sh compare DIR_A DIR_B    # one line per case, "same" or "DIFFERS: files";
#                                                     # exit status 1 if any case differs
#
# Each case directory holds cmd.txt (the command), rc.txt (its exit status), stdout.txt,
# stderr.txt and out/ (the files the command wrote). The commands run from OUTDIR on a copy of this
# repository's examples/ (OUTDIR/examples) with relative paths only, so no absolute path, neither
# of OUTDIR nor of the binary, reaches an output. Recordings are kept raw; `compare` masks.
#
# Masked by `compare` (replaced by "#"; the rest of each file is still compared byte for byte).
# Each is a wall-clock time or derived from one, so it changes between two runs of the same
# binary: found by recording the baseline twice; "*" = unchanged in those two, masked because it
# is a wall-clock time (or thread scheduling) as well.
#   report.json (run/replay): wall_time_s; stage_timing.<stage>.{p50,p99,max,mean}_ms;
#     schedule.frames_over_budget (frames whose wall time > period); output_stream.files.
#     "frames.csv".bytes (frames.csv holds the times); output_stream.writer_waits* (scheduling)
#   frames.csv (run/replay): columns input_ms scene_update_ms trace_ms sensor_ms output_ms frame_ms
#   image.json, sar.json: the "timing_s" object (per-step wall times)
#   tradeoff.csv: column cost_ms (measured wall ms)
#   stdout.txt: run/replay "wall N s", stage-time table numbers, "N frames over budget";
#     "in N s" (rcs, profile, tradeoff; scene gen "generated/written in N s"*), mom "fill N s",
#     "LU N s"; image "trace/image/optical/total N s"; sar "raw/image N s (ray tracing N %)";
#     scene preview "vertical field, N s"*
#   stderr.txt: rcs/profile progress "\r  direction|angle k/N (T s)" is redrawn on a timer, so the
#     number of redraws varies: a run of them is reduced to its last one, T masked; tradeoff's
#     "N ms" costs and "(trace N, sensor N)" splits
# Not compared, by name (pictures with wall-clock axes): timing.png (run/replay stage times),
#   tradeoff.png and tradeoff_frame.png (error against measured cost)
# Outputs are deterministic whatever the thread scheduling (two recordings agree once masked), so
# no thread count is forced (the CLI has no such option).
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
usage() { sed -n '2,8p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//' >&2; exit 2; }

# Cases: NAME then the arguments after the binary. Later cases may read earlier ones' out/.
cases=(
  "run_default      run --frames 40 --out run_default/out"
  "run_faulty_bus   run examples/faulty_bus.toml --frames 120 --out run_faulty_bus/out"
  "run_can_fd       run examples/can_fd_output.toml --frames 20 --out run_can_fd/out"
  "run_fog          run examples/fog_approach.toml --frames 20 --out run_fog/out"
  "run_movers       run examples/terrain_movers.toml --frames 20 --out run_movers/out"
  "run_gltf         run examples/gltf_targets.toml --frames 20 --out run_gltf/out"
  "run_ev           run examples/ev_radar_94ghz.toml --frames 10 --out run_ev/out"
  "run_nav_modbus   run --nav-modbus sim --frames 20 --out run_nav_modbus/out"
  "replay_default   replay run_default/out/bus_in.log --out replay_default/out"
  "replay_faulty    replay run_faulty_bus/out/bus_in.log examples/faulty_bus.toml --out replay_faulty/out"
  "scene_gen        scene gen airport --seed 1 --out scene_gen/out/airport.glb"
  "scene_info       scene info scene_gen/out/airport.glb --json"
  "scene_preview    scene preview scene_gen/out/airport.glb --out scene_preview/out/view.png --camera -40,-1300,90 --look-at 40,900,0 --fov-deg 14"
  "target_tri       scene target trihedral-tri --a-m 0.3 --out target_tri/out/tri.stl"
  "target_sphere    scene target sphere --a-m 0.01 --facet-m 0.002 --out target_sphere/out/s.obj"
  "rcs_trihedral    rcs --mesh target_tri/out/tri.stl --freq-hz 10e9 --theta-deg 0:90:181 --phi-deg 45 --pol HH,VV,HV --out rcs_trihedral/out/rcs.csv --plot rcs_trihedral/out/rcs.png"
  "rcs_map_stats    rcs --mesh target_tri/out/tri.stl --freq-sweep-hz 8e9:12e9:21 --theta-deg 0:90:91 --phi-deg 45 --pol HH,VV --window-deg 10 --out rcs_map_stats/out/map.csv --plot rcs_map_stats/out/map.png"
  "rcs_bistatic     rcs --mesh target_tri/out/tri.stl --freq-hz 10e9 --theta-deg 30 --phi-deg 0:90:31 --bistatic-theta-deg 40 --bistatic-phi-deg 45 --out rcs_bistatic/out/bist.csv"
  "rcs_mom_sphere   rcs --mesh target_sphere/out/s.obj --freq-hz 10e9 --method mom --out rcs_mom_sphere/out/s.csv"
  "profile_isar     profile --mesh target_tri/out/tri.stl --freq-sweep-hz 9e9:11e9:200 --theta-deg 54.7356 --phi-deg 40:50:64 --out profile_isar/out/profile.csv --plot profile_isar/out/profile.png"
  "sar_trihedrals   sar examples/sar_trihedrals.toml --out sar_trihedrals/out"
  "image_ev         image examples/ev_radar_94ghz.toml --time-s 52 --looks 10 --out image_ev/out --plot"
  "sigma0_asphalt   sigma0 --material asphalt --freq-hz 94e9 --theta-deg 0:88:89 --model total --out sigma0_asphalt/out/sigma0.csv --plot sigma0_asphalt/out/sigma0.png"
  "sigma0_bistatic  sigma0 --eps-r 5,0.09 --rms-height-m 5e-4 --corr-length-m 5e-3 --freq-hz 94e9 --model iem --theta-deg 40 --theta-s-deg 0:88:89 --phi-s-deg 0 --out sigma0_bistatic/out/sigma0.csv"
  "atten            atten --freq-hz 1e9:200e9:400 --rain-mmh 10 --fog-gm3 0.05 --veg-depth-m 20 --out atten/out/atten.csv --plot atten/out/atten.png"
  "ambiguity        ambiguity --out ambiguity/out"
  "ambiguity_train  ambiguity --train --out ambiguity_train/out"
  "ambiguity_ev     ambiguity examples/ev_radar_94ghz.toml --bandwidth-hz 100e6 --pulse-width-s 1e-6 --out ambiguity_ev/out"
  "tradeoff_quick   tradeoff --quick --out tradeoff_quick/out"
)

record() {
  local bin="$1" outdir="$2"
  if [ ! -f "$bin" ] || [ ! -x "$bin" ]; then
    echo "compare-outputs: BINARY '$bin' is missing or not executable" >&2; exit 2
  fi
  bin="$(cd "$(dirname "$bin")" && pwd)/$(basename "$bin")"
  [ -d "$root/examples" ] || { echo "compare-outputs: $root/examples not found" >&2; exit 2; }
  mkdir -p "$outdir"
  [ -z "$(ls -A "$outdir")" ] || { echo "compare-outputs: OUTDIR '$outdir' is not empty" >&2; exit 2; }
  cp -r "$root/examples" "$outdir/examples"
  cd "$outdir"
  local start=$SECONDS line name rest rc failed=()
  local -a argv
  for line in "${cases[@]}"; do
    read -r name rest <<< "$line"
    read -ra argv <<< "$rest"
    mkdir -p "$name/out"
    echo "radar-emu $rest" > "$name/cmd.txt"
    rc=0
    nice -n 10 "$bin" "${argv[@]}" > "$name/stdout.txt" 2> "$name/stderr.txt" || rc=$?
    echo "$rc" > "$name/rc.txt"
    [ "$rc" = 0 ] || failed+=("$name")
    printf '%-16s rc=%d  %4ds\n' "$name" "$rc" "$((SECONDS - start))"
  done
  echo "recorded ${#cases[@]} cases into $outdir in $((SECONDS - start)) s"
  # A failing command is recorded like any other (its rc.txt is compared), but said loudly.
  [ ${#failed[@]} = 0 ] || { echo "compare-outputs: non-zero exit status: ${failed[*]}" >&2; exit 1; }
}

compare() {
  local a="$1" b="$2"
  if [ ! -d "$a" ] || [ ! -d "$b" ]; then
    echo "compare-outputs: DIR_A '$a' and DIR_B '$b' must both be directories" >&2; exit 2
  fi
  /usr/bin/python3 - "$a" "$b" <<'PY'
import os, re, sys

EXCLUDED = {"timing.png", "tradeoff.png", "tradeoff_frame.png"}
NUM = rb"-?[0-9][0-9.eE+-]*"
TEXT = {  # file name -> [(regex, replacement)], in order
    "stdout.txt": [
        (rb"wall [0-9.]+ s", rb"wall # s"),
        (rb"(?m)^(    (?:input|scene_update|trace|sensor|output|frame)) +[0-9. ]+$", rb"\1 #"),
        (rb"[0-9]+ frames over budget", rb"# frames over budget"),
        (rb"\b(in|fill|LU|trace|image|optical|total|raw) [0-9.]+ s\b", rb"\1 # s"),
        (rb"ray tracing [0-9]+ %", rb"ray tracing # %"),
        (rb"(?m)(vertical field), [0-9.]+ s$", rb"\1, # s"),
    ],
    "stderr.txt": [
        (rb"(?:\r  [a-z]+ [0-9]+/[0-9]+ \([0-9.]+ s\))*\r  ([a-z]+ [0-9]+/[0-9]+) \([0-9.]+ s\)",
         rb"\r  \1 (# s)"),
        (rb"(?<![0-9.])[0-9]+ ms\b", rb"# ms"),
        (rb"\(trace [0-9]+, sensor [0-9]+\)", rb"(trace #, sensor #)"),
    ],
    "report.json": [
        (rb'("(?:wall_time_s|p50_ms|p99_ms|max_ms|mean_ms|frames_over_budget|writer_waits)": )' + NUM,
         rb"\1#"),
        (rb'("frames\.csv": \{\s*"bytes": )' + NUM, rb"\1#"),
    ],
    "image.json": [(rb'("timing_s": )\{[^{}]*\}', rb"\1#")],
    "sar.json": [(rb'("timing_s": )\{[^{}]*\}', rb"\1#")],
}
CSV = {  # file name -> columns masked (all before any quoted field)
    "frames.csv": {"input_ms", "scene_update_ms", "trace_ms", "sensor_ms", "output_ms", "frame_ms"},
    "tradeoff.csv": {"cost_ms"},
}

def mask(rel, data):
    name = os.path.basename(rel)
    for pattern, repl in TEXT.get(name, []):
        data = re.sub(pattern, repl, data)
    if name in CSV:
        lines = data.split(b"\n")
        cols = [i for i, c in enumerate(lines[0].split(b",")) if c.decode() in CSV[name]]
        for n in range(1, len(lines)):
            f = lines[n].split(b",", max(cols) + 1) if lines[n] else []
            for i in cols:
                if i < len(f):
                    f[i] = b"#"
            lines[n] = b",".join(f)
        data = b"\n".join(lines)
    return data

def files(case_dir):
    return {os.path.relpath(os.path.join(d, f), case_dir)
            for d, _, fs in os.walk(case_dir) for f in fs if f not in EXCLUDED}

def read(path):
    with open(path, "rb") as f:
        return f.read()

a, b = sys.argv[1:3]
cases = sorted({c for r in (a, b) for c in os.listdir(r) if os.path.isfile(os.path.join(r, c, "cmd.txt"))})
bad = 0
for case in cases:
    ca, cb = os.path.join(a, case), os.path.join(b, case)
    fa, fb = files(ca), files(cb)  # empty when the case's directory is missing
    diff = []
    for rel in sorted(fa | fb):
        if rel not in fa or rel not in fb:
            diff.append(rel + (" (only in A)" if rel in fa else " (only in B)"))
            continue
        da, db = read(os.path.join(ca, rel)), read(os.path.join(cb, rel))
        if da != db and mask(rel, da) != mask(rel, db):
            diff.append(rel)
    if not fa or not fb:
        diff = ["(case missing in " + ("A" if not fa else "B") + ")"]
    print(f"{case}: " + ("same" if not diff else "DIFFERS: " + " ".join(diff)))
    bad += bool(diff)
sys.exit(1 if bad else 0)
PY
}

[ $# -eq 3 ] || usage
case "$1" in
  record) record "$2" "$3" ;;
  compare) compare "$2" "$3" ;;
  *) usage ;;
esac
