#!/usr/bin/env bash
# The layering test (docs/architecture.md, "Folders and direction"): fails when a folder includes
# a header of a folder it must not depend on, or when Embree is included outside scene/*.cpp.
#
#   app, python -> tools -> loop -> radar -> scene
#                    |        |  \-> sim_bus -> io,  timing
#                    v        v
#                  plot, config, scene, radar          (all may use common)
#
# Usage: scripts/check-layering.sh [ROOT]       checks the tree at ROOT (default: this checkout)
#        scripts/check-layering.sh --self-test   plants an upward include in a copy of this
#                                                checkout and fails unless the check catches it
set -euo pipefail
shopt -s nullglob
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

if [ "${1:-}" = "--self-test" ]; then
  tmp="$(mktemp -d)"
  trap 'rm -rf "$tmp"' EXIT
  for d in common timing io sim_bus scene radar config plot loop tools app python; do
    [ -d "$here/$d" ] && cp -r "$here/$d" "$tmp/$d"
  done
  "$0" "$tmp" >/dev/null || { echo "layering self-test: the unplanted copy fails" >&2; exit 1; }
  # Each plant: FILE|LINE that the check must refuse.
  plants=(
    'loop/closed_loop.cpp|#include "tools/rcs.hpp"'
    'radar/em/sbr.cpp|#include "loop/scenario.hpp"'
    'scene/scene.cpp|#include "radar/em/sbr.hpp"'
    'loop/outputs/output_stream.cpp|#include "loop/closed_loop.hpp"'
    'python/radar_emu_module.cpp|#include "app/cmd.hpp"'
    'radar/em/rcs.cpp|#include <embree3/rtcore.h>'
  )
  for plant in "${plants[@]}"; do
    file="${plant%%|*}"
    line="${plant#*|}"
    cp "$tmp/$file" "$tmp/$file.orig"
    printf '%s\n' "$line" >>"$tmp/$file"
    if "$0" "$tmp" >/dev/null 2>&1; then
      echo "layering self-test: '$line' planted in $file was not caught" >&2
      exit 1
    fi
    mv "$tmp/$file.orig" "$tmp/$file"
    echo "layering self-test: caught '$line' in $file"
  done
  echo "layering self-test: ok"
  exit 0
fi

root="${1:-$here}"
cd "$root"
status=0
# forbid DIR INCLUDED...: no file under DIR includes "INCLUDED/..." (or <INCLUDED/...>).
forbid() {
  local dir="$1"
  shift
  [ -d "$dir" ] || return 0
  for other in "$@"; do
    if grep -rnE "#include [<\"]${other}/" "$dir" --include='*.hpp' --include='*.cpp'; then
      echo "layering: $dir/ must not include $other/" >&2
      status=1
    fi
  done
}
ours=(common timing io sim_bus scene radar config plot loop tools app)
# but_common DIR: DIR includes nothing of ours but common/.
but_common() {
  local dir="$1" others=()
  for m in "${ours[@]}"; do
    [ "$m" != common ] && [ "$m" != "$dir" ] && others+=("$m")
  done
  forbid "$dir" "${others[@]}"
}
for leaf in common timing io scene config plot; do
  but_common "$leaf"
done
forbid sim_bus timing scene radar config plot loop tools app
forbid radar timing io sim_bus config plot loop tools app
forbid loop tools app
forbid tools app
forbid python app
# Inside loop/, the outputs see the record types (loop/frame_record.hpp), never the loop itself.
if grep -rnE '#include [<"]loop/closed_loop\.hpp' loop/outputs 2>/dev/null; then
  echo "layering: loop/outputs/ must not include loop/closed_loop.hpp (use loop/frame_record.hpp)" >&2
  status=1
fi
# Embree stays behind scene's API (style.md item 2): only scene/*.cpp include it.
embree_free=()
for d in common timing io sim_bus radar config plot loop tools app python; do
  [ -d "$d" ] && embree_free+=("$d")
done
if grep -rnE '#include [<"]embree' --include='*.hpp' --include='*.cpp' "${embree_free[@]}" \
  scene/*.hpp scene/*/*.hpp 2>/dev/null; then
  echo "layering: Embree may only be included from scene/*.cpp" >&2
  status=1
fi
[ $status -eq 0 ] && echo "layering: ok"
exit $status
