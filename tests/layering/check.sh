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

# The helpers set a variable instead of printing: a command substitution
# per #include line made this check take seconds.

# rank LAYER: the layer's rank in $rank.
rank() {
  case $1 in
    core) rank=0 ;; simulator) rank=1 ;; runtime) rank=2 ;; shim) rank=3 ;;
    tools|server) rank=4 ;;
    *) rank='' ;;
  esac
}

# public_layer HEADER: the layer of a public header in $layer_of ('' if none).
public_layer() {
  case $1 in
    common.h|strategy.h|config.h) layer_of=core ;;
    sim.h|trace.h|layout.h) layer_of=simulator ;;
    mesh.h|profile.h|table.h|synth.h|session.h|replay.h|tag.h|sites.h|agent.h|guard.h)
      layer_of=runtime ;;
    *) layer_of='' ;;
  esac
}

status=0
for h in include/emm/*.h; do
  name=${h#include/emm/}
  public_layer "$name"
  if [ -z "$layer_of" ]; then
    echo "$h: public header without a layer (add it to tests/layering/check.sh)"
    status=1
  fi
done

for layer in core simulator runtime shim tools server; do
  [ -d "$layer" ] || continue
  rank $layer; mine=$rank
  for f in $(find "$layer" -type f \( -name '*.c' -o -name '*.cpp' -o -name '*.h' \) | sort); do
    # Every #include "..." of the file, with its line number. The line's
    # first '"' opens the name: only blanks, '#' and "include" come before.
    grep -n '^[[:space:]]*#[[:space:]]*include[[:space:]]*"' "$f" | while IFS= read -r line; do
      num=${line%%:*}
      inc=${line#*\"}
      inc=${inc%%\"*}
      case $inc in
        emm/*) public_layer "${inc#emm/}"; owner=$layer_of ;;
        */*) owner='' ;;  # a path into another tree (a system or package header)
        *)
          owner=''
          for l in core simulator runtime shim tools server; do
            if [ -f "$l/$inc" ]; then owner=$l; break; fi
          done
          ;;
      esac
      [ -n "$owner" ] || continue
      rank "$owner"; theirs=$rank
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
