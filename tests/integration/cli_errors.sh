#!/usr/bin/env bash
# radar-emu's command line: bad input exits non-zero with one line that says what is wrong;
# --help works for every subcommand.
set -u
exe="$1"; dir="$2"
mkdir -p "$dir"
fails=0
expect_error() {  # expect_error PATTERN ARGS...
  local pattern="$1"; shift
  local err rc
  err=$(timeout 120 "$exe" "$@" 2>&1 >/dev/null); rc=$?
  if [ $rc -eq 0 ]; then echo "FAIL: '$*' exited 0"; fails=$((fails+1)); return; fi
  if [ $rc -eq 124 ]; then echo "FAIL: '$*' did not fail within 120 s"; fails=$((fails+1)); return; fi
  if [ "$(printf '%s\n' "$err" | grep -c .)" -gt 2 ]; then
    echo "FAIL: '$*' printed more than a short error:"; printf '%s\n' "$err"; fails=$((fails+1))
  fi
  if ! printf '%s' "$err" | grep -q -- "$pattern"; then
    echo "FAIL: '$*' error does not mention '$pattern': $err"; fails=$((fails+1))
  fi
}
printf '[run]\nframes = 0\n' > "$dir/zero.toml"
printf '[radar]\ncarrier_hz = "fast"\n' > "$dir/type.toml"
printf '[run\n' > "$dir/syntax.toml"
printf '[scene]\nfile = "missing.glb"\n' > "$dir/scene.toml"
expect_error "zero.toml: \[run\] frames" run "$dir/zero.toml"
expect_error "carrier_hz: expected a number" run "$dir/type.toml"
expect_error "syntax.toml:1" run "$dir/syntax.toml"
expect_error "missing.glb" run "$dir/scene.toml"
expect_error "nope.toml" run "$dir/nope.toml"
# [[target]] tables: the file, the table's number and the key (docs/scene_format.md).
printf '[[target]]\nbuiltin = "jeep"\nposition_enu_m = [0, 0, 0]\n[[target]]\nbuiltin = "box"\nsize_m = [1, -1, 2]\nposition_enu_m = [0, 0, 0]\n' > "$dir/target_size.toml"
printf '[[target]]\nbuiltin = "jeep"\nposition_enu_m = [0, 0, 0]\nspeed = 3\n' > "$dir/target_key.toml"
printf '[scene]\nbuiltin = "default"\n[[target]]\nbuiltin = "jeep"\nposition_enu_m = [9000, 0, 0]\non_ground = true\n' > "$dir/target_ground.toml"
expect_error "target_size.toml: \[\[target\]\] #2 size_m: -1 is outside (0, 10000\]" run "$dir/target_size.toml"
expect_error "target_key.toml: \[\[target\]\] #1 speed: unknown key (known: name, " run "$dir/target_key.toml"
expect_error "target_ground.toml: \[\[target\]\] #1: on_ground: no ground below" run "$dir/target_ground.toml"
expect_error "frames" run --frames 0
# Output paths are checked at setup, before any frame runs: a million-frame run (hours) with a
# bad --out or --trace-events path fails at once instead of at its end.
expect_error "zero.toml/out: cannot create the output directory" run --frames 1000000 --out "$dir/zero.toml/out"
expect_error "zero.toml/t.json: cannot open for writing" run --frames 1000000 --trace-events "$dir/zero.toml/t.json"
expect_error "unknown target 'cone'" scene target cone --out "$dir/x.obj"
expect_error "--a-m: -1 is outside (0, 100000\] m" scene target plate --a-m -1 --out "$dir/x.obj"
expect_error "cannot open for writing" scene target box --out "$dir/no/such/dir/x.stl"
if ! "$exe" scene target trihedral-tri --a-m 0.3 --out "$dir/t.stl" >/dev/null; then
  echo "FAIL: scene target trihedral-tri"; fails=$((fails+1))
fi
# Binary STL: 80-byte header + 4-byte count + 50 bytes per triangle (3 triangles here).
if [ "$(stat -c %s "$dir/t.stl")" -ne $((84 + 50 * 3)) ]; then
  echo "FAIL: t.stl size"; fails=$((fails+1))
fi
# rcs / profile: every bad option is named.
m="$dir/t.stl"
expect_error "exactly one of --freq-hz and --freq-sweep-hz" rcs --mesh "$m"
expect_error "--freq-sweep-hz: N must be a whole number" rcs --mesh "$m" --freq-sweep-hz 1e9:2e9:0
expect_error "--theta-deg: 'abc' is not a finite number" rcs --mesh "$m" --freq-hz 1e10 --theta-deg abc
expect_error "--pol: 'XY' is not one of" rcs --mesh "$m" --freq-hz 1e10 --pol HH,XY
expect_error "--material 'glass'" rcs --mesh "$m" --freq-hz 1e10 --material glass
expect_error "unknown mesh format" rcs --mesh "$dir/zero.toml" --freq-hz 1e10
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl glass\nf 1 2 3\n' > "$dir/glass.obj"
expect_error "material 'glass' is not a conductor" rcs --mesh "$dir/glass.obj" --freq-hz 1e10
expect_error "over the limit" rcs --mesh "$m" --freq-hz 1e15 -q
expect_error "--overlay needs --plot" rcs --mesh "$m" --freq-hz 1e10 --overlay "$m=x"
expect_error "expected FILE=LABEL" rcs --mesh "$m" --freq-hz 1e10 --plot "$dir/o.png" --overlay nolabel
expect_error "--edge-turn-deg must be in" rcs --mesh "$m" --freq-hz 1e10 --edge-turn-deg 200
expect_error "N >= 2" profile --mesh "$m" --freq-hz 1e10
expect_error "theta or phi, not both" profile --mesh "$m" --freq-sweep-hz 9e9:1e10:8 --theta-deg 0:1:3 --phi-deg 0:1:3
if ! "$exe" rcs --mesh "$dir/glass.obj" --freq-hz 1e10 --material glass=6,0.2 -q --out "$dir/g.csv"; then
  echo "FAIL: rcs with a dielectric material"; fails=$((fails+1))
fi
# ambiguity / the sensor's scenario keys: one-line errors naming the option or key.
expect_error "--points: Value 3 not in range 11 to 2001" ambiguity --points 3 --out "$dir/amb"
expect_error "--train needs PRI >= 2 T" ambiguity --train --prf-hz 400e3 --out "$dir/amb"
printf '[radar]\nwaveform = "cw"\n' > "$dir/wave.toml"
expect_error "wave.toml: \[radar\] waveform: unknown value \"cw\" (known: pulsed_lfm, fmcw)" run "$dir/wave.toml"
printf '[radar]\nswath_start_m = 100.0\n' > "$dir/blind.toml"
expect_error "swath_start_m must be >= the blind range" run "$dir/blind.toml"
printf '[detector]\ncfar_training_cells = 900\n' > "$dir/cfar.toml"
expect_error "cfar.toml: \\[detector\\] cfar: range_training" run "$dir/cfar.toml"
# sigma0 / atten: one-line errors for bad parameters and out-of-range frequencies.
expect_error "rms height must be finite and >= 0" sigma0 --eps-r 4,0.1 --rms-height-m -0.001 --corr-length-m 0.01 --freq-hz 35e9 --out "$dir/s.csv"
expect_error "IM is the loss" sigma0 --eps-r 4,-0.1 --rms-height-m 0.001 --corr-length-m 0.01 --freq-hz 35e9 --out "$dir/s.csv"
expect_error "unknown material 'lava'" sigma0 --material lava --freq-hz 35e9 --out "$dir/s.csv"
expect_error "L, S and C band" sigma0 --material grass --model empirical --freq-hz 94e9 --out "$dir/s.csv"
expect_error "no published empirical curve for asphalt" sigma0 --material asphalt --model empirical --freq-hz 5e9 --out "$dir/s.csv"
expect_error "perfect conductor" sigma0 --material metal --freq-hz 35e9 --out "$dir/s.csv"
expect_error "unknown model 'mom'" sigma0 --material grass --model mom --freq-hz 35e9 --out "$dir/s.csv"
expect_error "incidence angles must be in" sigma0 --material grass --theta-deg 0:95:3 --freq-hz 35e9 --out "$dir/s.csv"
expect_error "beyond 1000" sigma0 --eps-r 4,0.1 --rms-height-m 1 --corr-length-m 5 --freq-hz 94e9 --out "$dir/s.csv"
expect_error "--freq-hz: 5e+08 is outside \[1e+09, 1e+12\] Hz" atten --freq-hz 0.5e9 --out "$dir/a.csv"
expect_error "--rain-mmh: -3 is outside \[0, 500\] mm/h" atten --freq-hz 35e9 --rain-mmh -3 --out "$dir/a.csv"
expect_error "--veg-depth-m must be" atten --freq-hz 10e9 --veg-depth-m -2 --out "$dir/a.csv"
# scene gen / info / preview: one-line errors naming the kind, option or file.
expect_error "unknown scene kind 'city'" scene gen city --out "$dir/c.glb"
expect_error "--seed: 'abc' is not a whole number" scene gen terrain --seed abc --out "$dir/t.glb"
expect_error "--seed: '-3' is not a whole number" scene gen terrain --seed -3 --out "$dir/t.glb"
expect_error "--out: $dir/t.obj: cannot write a '.obj' file (expected .glb, .gltf)" scene gen terrain --out "$dir/t.obj"
expect_error "does not exist" scene gen terrain --out "$dir/no/such/dir/t.glb"
expect_error "nope.glb" scene info "$dir/nope.glb"
expect_error "zero.toml" scene info "$dir/zero.toml"
expect_error "nope.glb" scene preview "$dir/nope.glb" --out "$dir/v.png"
expect_error "--camera: '1,2' is not three numbers" scene preview "$dir/nope.glb" --camera 1,2 --out "$dir/v.png"
expect_error "--width: Value 0 not in range 1 to 16384" scene preview "$dir/nope.glb" --width 0 --out "$dir/v.png"
for sub in "scene gen" "scene info" "scene preview"; do
  if ! "$exe" $sub --help >/dev/null 2>&1; then echo "FAIL: '$sub --help'"; fails=$((fails+1)); fi
done
# Bus backends and replay (issue 6).
expect_error "--can: unknown backend 'bogus'" run --can bogus
expect_error "--can: unknown option 'bitrate=5'" run --can sim,bitrate=5
expect_error "add --realtime" run --can socketcan:can0
expect_error "add --realtime" run --nav-modbus tcp:127.0.0.1:1502
expect_error "--modbus-server: 'x:y'" run --modbus-server x:y --frames 1
printf '(1767225600.000000) can0 137#0102\nnot a candump line\n' > "$dir/bad.log"
expect_error "bad.log:2" replay "$dir/bad.log"
expect_error "nope.log" replay "$dir/nope.log"
printf '[faults]\ndelay_s = 0.01\njitter_s = 0.02\n' > "$dir/jitter.toml"
expect_error "\[faults\] jitter_s" run "$dir/jitter.toml"
for sub in "" run replay scene "scene target" rcs profile sigma0 atten; do
  if ! "$exe" $sub --help >/dev/null 2>&1; then echo "FAIL: '$sub --help'"; fails=$((fails+1)); fi
done
[ $fails -eq 0 ] && echo "cli errors: ok"
exit $fails
