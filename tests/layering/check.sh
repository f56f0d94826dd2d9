#!/bin/sh
# The layering rule of docs/architecture.md: core < simulator < runtime <
# shim < tools (and server, emm-session, beside tools), and no source
# includes a header of a layer above its own.
# Internal headers belong to the folder they sit in; each public header in
# include/emm/ belongs to the layer that implements it (the table below: a
# public header missing from it is an error, so a new one gets a layer).
#
# usage: check.sh ROOT    (exit 0: clean; 1: violations, one line each)
set -eu
root=${1:?usage: check.sh ROOT}
cd "$root"

# layer ranks
rank() {
  case $1 in
    core) echo 0 ;; simulator) echo 1 ;; runtime) echo 2 ;; shim) echo 3 ;;
    tools|server) echo 4 ;;
    *) echo '' ;;
  esac
}

# The public headers and their layers.
public_layer() {
  case $1 in
    common.h|strategy.h|config.h) echo core ;;
    sim.h|trace.h|layout.h) echo simulator ;;
    mesh.h|profile.h|table.h|synth.h|session.h|replay.h|tag.h|sites.h|agent.h|guard.h)
      echo runtime ;;
    *) echo '' ;;
  esac
}

status=0
for h in include/emm/*.h; do
  name=${h#include/emm/}
  if [ -z "$(public_layer "$name")" ]; then
    echo "$h: public header without a layer (add it to tests/layering/check.sh)"
    status=1
  fi
done

for layer in core simulator runtime shim tools server; do
  [ -d "$layer" ] || continue
  mine=$(rank $layer)
  for f in $(find "$layer" -type f \( -name '*.c' -o -name '*.cpp' -o -name '*.h' \) | sort); do
    # Every #include "..." of the file, with its line number.
    grep -n '^[[:space:]]*#[[:space:]]*include[[:space:]]*"' "$f" | while IFS= read -r line; do
      num=${line%%:*}
      inc=$(printf '%s\n' "$line" | sed 's/.*#[[:space:]]*include[[:space:]]*"\([^"]*\)".*/\1/')
      case $inc in
        emm/*) owner=$(public_layer "${inc#emm/}") ;;
        */*) owner='' ;;  # a path into another tree (a system or package header)
        *)
          owner=''
          for l in core simulator runtime shim tools server; do
            if [ -f "$l/$inc" ]; then owner=$l; break; fi
          done
          ;;
      esac
      [ -n "$owner" ] || continue
      theirs=$(rank "$owner")
      if [ "$theirs" -gt "$mine" ]; then
        echo "$f:$num: includes \"$inc\", a header of $owner, above $layer"
        echo violation >> "${TMPDIR:-/tmp}/emm-layering.$$"
      fi
    done
  done
done
if [ -e "${TMPDIR:-/tmp}/emm-layering.$$" ]; then
  rm -f "${TMPDIR:-/tmp}/emm-layering.$$"
  status=1
fi
[ $status -eq 0 ] && echo "layering: clean (core < simulator < runtime < shim < tools)"
exit $status
