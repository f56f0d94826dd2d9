#!/bin/sh
# The fault capture's cost per window access, beside the valgrind capture
# (issue 27's benchmark; not a test: it times things).
#
#   sh bench/fault_overhead.sh BUILD [FACES]
#
# For each program, median wall times of 3 runs of: the program natively,
# `emm run --capture fault` and `emm run --capture valgrind` (both with
# --compare baselines, the default). Printed:
#   - us per window access: (fault run - native run) / the fault report's
#     "accesses" (the window's records: the access faults, each a SIGSEGV,
#     an instruction run in a slot or under the trap flag, a SIGTRAP, two
#     mprotect calls; and the session's decision and simulation of the
#     window, which a window access pays its share of);
#   - fault / valgrind: the fault run's wall time over the valgrind
#     capture's (which captures and simulates the whole run);
#   - the session's capture line for each (`emm run`'s summary).
# Programs:
#   1. build/bin/curve_tracing (the plain build of examples/curve_tracing.c)
#      on a generated mesh of FACES faces (default 100,000): its arrays are
#      tagged by its own emm_tag_* calls.
#   2. admesh (Debian's admesh) repairing a binary STL of the same mesh
#      (made with ctmconv, Debian's openctm-tools), tagged by one rule on its
#      facet array; skipped when admesh or ctmconv is not installed.
# The valgrind runs are skipped (ratio "-") when Valgrind or emm's tool is
# missing. Meshes are cached in BUILD/bench/.
set -u
[ $# -ge 1 ] || { echo "usage: sh bench/fault_overhead.sh BUILD [FACES]" >&2; exit 2; }
B=$(cd "$1" && pwd) || exit 1
FACES=${2:-100000}
EMM=$B/bin/emm CT=$B/bin/curve_tracing
for f in "$EMM" "$CT" "$B/lib/libemmshim.so"; do
  [ -e "$f" ] || { echo "fault_overhead: $f is not built" >&2; exit 1; }
done
VG=1
{ command -v valgrind >/dev/null && [ -e "$B/lib/emm/valgrind/emm-amd64-linux" ]; } || VG=
mkdir -p "$B/bench" || exit 1
MESH=$B/bench/fault$FACES.off
if [ ! -s "$MESH" ]; then
  "$EMM" mesh gen --faces "$FACES" -o "$MESH.tmp.off" >/dev/null && mv "$MESH.tmp.off" "$MESH" || exit 1
fi
TMP=$(mktemp -d) || exit 1
trap 'rm -rf "$TMP"' EXIT
unset EMM_TAG EMM_REPORT EMM_TRACE EMM_PROFILE_DUMP EMM_PROFILE EMM_CAPTURE EMM_LOG EMM_STRATEGY

now() { date +%s%N; }
TIME=
[ -x /usr/bin/time ] && TIME=/usr/bin/time
# median3 CMD...: the median wall time of three runs in ns, and the median
# CPU time (user + system, children included; "-" without /usr/bin/time) in
# seconds, which moves less when other work shares the machine (stderr of
# the last run in $TMP/err).
median3() {
  for _ in 1 2 3; do
    t0=$(now)
    if [ -n "$TIME" ]; then
      "$TIME" -f '%U %S' -o "$TMP/cpu" "$@" > /dev/null 2> "$TMP/err"
    else
      "$@" > /dev/null 2> "$TMP/err"
    fi || { cat "$TMP/err" >&2; echo "fault_overhead: $* failed" >&2; exit 1; }
    wall=$(( $(now) - t0 ))
    cpu=-
    [ -n "$TIME" ] && cpu=$(tail -1 "$TMP/cpu" | awk '{ printf "%.3f", $1 + $2 }')
    echo "$wall $cpu"
  done > "$TMP/times"
  w=$(awk '{ print $1 }' "$TMP/times" | sort -n | sed -n 2p)
  c=$(awk '{ print $2 }' "$TMP/times" | sort -n | sed -n 2p)
  echo "$w $c"
}
accesses() {
  /usr/bin/python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["accesses"])' "$1"
}

# bench NAME RULES PROGRAM ARGS...
bench() {
  name=$1 rules=$2
  shift 2
  # (two words each: the wall and the CPU time)
  r=$(median3 "$@") && [ -n "$r" ] || exit 1
  # shellcheck disable=SC2086
  set -- $r "$@"
  tn=$1 cn=$2
  shift 2
  [ -n "$rules" ] && export EMM_TAG="$rules"
  r=$(median3 "$EMM" run --capture fault --report "$TMP/f.json" -- "$@") &&
    [ -n "$r" ] || exit 1
  # shellcheck disable=SC2086
  set -- $r "$@"
  tf=$1 cf=$2
  shift 2
  fline=$(grep 'simulated:' "$TMP/err" | sed 's/^emm: *//; s/; its share of the run.*//')
  af=$(accesses "$TMP/f.json") || exit 1
  tv=- cv=- vline="valgrind capture not run (valgrind or emm's tool missing)"
  if [ -n "$VG" ]; then
    r=$(median3 "$EMM" run --capture valgrind -- "$@") && [ -n "$r" ] || exit 1
    # shellcheck disable=SC2086
    set -- $r "$@"
    tv=$1 cv=$2
    shift 2
    vline=$(grep 'simulated:' "$TMP/err" | sed 's/^emm: *//')
  fi
  awk -v name="$name" -v tn="$tn" -v tf="$tf" -v tv="$tv" -v cn="$cn" -v cf="$cf" -v cv="$cv" \
      -v af="$af" 'BEGIN {
    printf "%s (medians of 3): native %.3f s (cpu %s), fault capture %.3f s (cpu %s)", name,
           tn / 1e9, cn, tf / 1e9, cf
    if (tv != "-") printf ", valgrind capture %.3f s (cpu %s)", tv / 1e9, cv
    printf "\n  fault capture: %.1f us per window access", (tf - tn) / 1e3 / af
    if (cf != "-") printf " (cpu %.1f us)", (cf - cn) * 1e6 / af
    printf ", %d accesses", af
    if (tv != "-") {
      printf "; fault / valgrind: %.2f", tf / tv
      if (cf != "-" && cv > 0) printf " (cpu %.2f)", cf / cv
    }
    printf "\n" }'
  echo "  fault:    $fline"
  echo "  valgrind: $vline"
  unset EMM_TAG
}

echo "load: $(cut -d' ' -f1-3 /proc/loadavg) ($(nproc) cores)"
bench "curve_tracing, $FACES faces" "" "$CT" "$MESH" || exit 1
if command -v admesh >/dev/null && command -v ctmconv >/dev/null; then
  STL=$B/bench/fault$FACES.stl
  if [ ! -s "$STL" ]; then
    ctmconv "$MESH" "$STL.tmp.stl" >/dev/null && mv "$STL.tmp.stl" "$STL" || exit 1
  fi
  # admesh's facets: 52-byte records (a normal, three corners, two bytes
  # of attributes, padded), the corners 12 bytes in.
  bench "admesh -b, $FACES facets" 'soup:site=stl_allocate,min=1000000,stride=52,corners=12:f32' \
    admesh -b "$TMP/o.stl" "$STL" || exit 1
else
  echo "admesh: skipped (Debian packages admesh and openctm-tools)"
fi
