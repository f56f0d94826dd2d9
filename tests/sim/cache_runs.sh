#!/bin/sh
# Runs of one program give the same reference cache (and direct reads): the
# program's arrays land elsewhere each run (ASLR; and within their page as
# emm's own allocations before them vary: the second run reads a machine
# file of default values), and the models place them anew (docs/machine.md
# "Addresses"). Before, the cache's misses moved by some 0.3 % between runs
# of region growing on 5,000 faces.
# usage: cache_runs.sh EMM WORKDIR PROGRAM
#   PROGRAM: region_growing (its sancov build when there is one)
set -u
EMM=$1 W=$2 PROG=$3
rm -rf "$W" && mkdir -p "$W" || exit 1
[ "$(cat /proc/sys/kernel/randomize_va_space 2>/dev/null)" = 0 ] &&
  echo "note: ASLR is off here; the runs' addresses do not move"
"$EMM" mesh gen --faces 5000 --seed 2 -o "$W/m.off" >/dev/null || exit 1
printf '# the defaults\nclock.mhz = 400\ncache.line = 64\n' >"$W/same.ini"
for i in 1 2 3; do
  machine=
  [ $i = 2 ] && machine="--machine $W/same.ini"
  # shellcheck disable=SC2086
  "$EMM" run $machine --strategy tiles+convolution@32 --report "$W/r$i.json" -- "$PROG" "$W/m.off" \
    >/dev/null 2>"$W/err$i" || { cat "$W/err$i"; echo "FAIL: run $i"; exit 1; }
  python3 - "$W/r$i.json" >"$W/c$i" <<'PY' || { echo "FAIL: report $i"; exit 1; }
import json, sys
r = json.load(open(sys.argv[1]))
for s in r["results"]:
    if s["strategy"] in ("cache", "direct"):
        print(s["strategy"], s["cycles"]["total"], json.dumps(s.get("cache"), sort_keys=True))
PY
  [ "$(grep -c . "$W/c$i")" = 2 ] || { cat "$W/c$i"; echo "FAIL: run $i: no cache and direct results"; exit 1; }
done
cat "$W/c1"
for i in 2 3; do
  cmp -s "$W/c1" "$W/c$i" || { diff "$W/c1" "$W/c$i"; echo "FAIL: runs 1 and $i differ"; exit 1; }
done
echo "cache_runs: three runs, the same cache and direct reads"
