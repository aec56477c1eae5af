#!/usr/bin/env bash
# Fails if a module includes a header from a module it must not depend on (docs/architecture.md)
# or if Embree is included outside scene/*.cpp.
set -euo pipefail
root="${1:-$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)}"
cd "$root"
status=0
forbid() {  # forbid MODULE INCLUDED...
  local module="$1"; shift
  for other in "$@"; do
    if grep -rnE "#include [<\"]${other}/" "$module" --include='*.hpp' --include='*.cpp' ; then
      echo "layering: $module/ must not include $other/" >&2
      status=1
    fi
  done
}
forbid timing io sim_bus scene radar emulator
forbid io timing sim_bus scene radar emulator
forbid sim_bus timing scene radar emulator
forbid scene timing io sim_bus radar emulator
forbid radar timing io sim_bus emulator
if grep -rnE '#include [<"]embree' --include='*.hpp' --include='*.cpp' \
     timing io sim_bus radar emulator scene/*.hpp 2>/dev/null; then
  echo "layering: Embree may only be included from scene/*.cpp" >&2
  status=1
fi
[ $status -eq 0 ] && echo "layering: ok"
exit $status
