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
  err=$("$exe" "$@" 2>&1 >/dev/null); rc=$?
  if [ $rc -eq 0 ]; then echo "FAIL: '$*' exited 0"; fails=$((fails+1)); return; fi
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
expect_error "frames" run --frames 0
expect_error "unknown target 'cone'" scene target cone --out "$dir/x.obj"
expect_error "a_m must be a positive number" scene target plate --a-m -1 --out "$dir/x.obj"
expect_error "cannot open for writing" scene target box --out "$dir/no/such/dir/x.stl"
if ! "$exe" scene target trihedral-tri --a-m 0.3 --out "$dir/t.stl" >/dev/null; then
  echo "FAIL: scene target trihedral-tri"; fails=$((fails+1))
fi
# Binary STL: 80-byte header + 4-byte count + 50 bytes per triangle (3 triangles here).
if [ "$(stat -c %s "$dir/t.stl")" -ne $((84 + 50 * 3)) ]; then
  echo "FAIL: t.stl size"; fails=$((fails+1))
fi
for sub in "" run scene "scene target"; do
  if ! "$exe" $sub --help >/dev/null 2>&1; then echo "FAIL: '$sub --help'"; fails=$((fails+1)); fi
done
[ $fails -eq 0 ] && echo "cli errors: ok"
exit $fails
