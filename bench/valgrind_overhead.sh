#!/bin/sh
# The valgrind capture's cost (issue 14's benchmark; not a test: it times
# things).
#
#   sh bench/valgrind_overhead.sh [--smooth-only] BUILD [FACES] [PASSES]
#
# --smooth-only: the smoothing program's rows without Lackey, and not the
# decimater (minutes instead of an hour on a busy machine: Lackey alone
# takes about 4,000 times the native run).
#
# Two programs, each with one input, in one run; wall times, median of 3,
# as ratios over the program's native run.
#
# 1. examples/smooth.c (a plain C program with its own OBJ loader, tagged by
#    EMM_TAG rules) on a generated mesh of FACES faces (default 100,000),
#    PASSES Laplacian passes (default 10): the worst case for emm, nearly
#    every instruction a mesh access.
#      emm        emm run --capture valgrind --compare baselines (the whole run
#                 captured, decided, and simulated under the answer, the
#                 contest's finalists, direct reads and the reference cache;
#                 the session natively in emm-session beside the program)
#      no phases  the same with --no-phases (the run not probed for phases)
#      thesis     the same with --no-phases --finalists 0: the thesis' method
#                 (the window's prediction stands, one pattern for the run),
#                 still simulated over the whole run beside the baselines
#      untagged   the same without rules: Valgrind, emm's tool and the shim,
#                 nothing tagged (the instrumentation's own cost)
#      none       valgrind --tool=none (Valgrind's base)
#      sancov     the sancov build under emm run (the session's own cost,
#                 natively, in the program's process)
#      cachegrind valgrind --tool=cachegrind (its cache simulation on)
#      lackey     valgrind --tool=lackey --trace-mem=yes (every access printed)
# 2. OpenMesh's decimater (OpenMesh-commandlineDecimater, Debian's
#    libopenmesh-apps) on the glmark2 bunny, a program nobody here wrote,
#    tagged by one rule: emm, none and cachegrind (Lackey would take hours).
#    Skipped when the app or the bunny is not installed.
# Targets: emm (the defaults) no slower than Cachegrind (issue 14); the
# sancov build under emm run at most half of Cachegrind's time (issue 29).
set -u
SMOOTH_ONLY=
[ "${1:-}" = --smooth-only ] && { SMOOTH_ONLY=1; shift; }
[ $# -ge 1 ] || { echo "usage: sh bench/valgrind_overhead.sh [--smooth-only] BUILD [FACES] [PASSES]" >&2; exit 2; }
B=$(cd "$1" && pwd) || exit 1
FACES=${2:-100000} PASSES=${3:-10}
EMM=$B/bin/emm PROG=$B/bin/smooth SANCOV=$B/bin/smooth.sancov
for f in "$EMM" "$PROG" "$SANCOV" "$B/lib/emm/valgrind/emm-amd64-linux"; do
  [ -e "$f" ] || { echo "valgrind_overhead: $f is not built" >&2; exit 1; }
done
command -v valgrind >/dev/null || { echo "valgrind_overhead: valgrind is not installed" >&2; exit 1; }
NAME=valgrind_overhead
# captured REPORT: the element accesses the run simulated (coverage, not the
# window's), or "?".
captured() {
  python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["coverage"]["element_accesses"])' \
    "$1" 2>/dev/null || echo "?"
}
. "$(dirname "$0")/smooth_setup.sh"
# median3 CMD...: the median wall time of three runs, in seconds.
median3() {
  for i in 1 2 3; do
    t0=$(now)
    "$@" > "$TMP/out" 2> "$TMP/err" || { cat "$TMP/err" >&2; echo "valgrind_overhead: $* failed" >&2; exit 1; }
    echo $(( $(now) - t0 ))
  done | sort -n | sed -n 2p | awk '{ printf "%.3f\n", $1 / 1e9 }'
}

native=$(median3 "$PROG" "$MESH" "$PASSES") || exit 1
cp "$TMP/out" "$TMP/native.out"
emm=$(median3 "$EMM" run --capture valgrind --compare baselines --tag "$TAG" --report "$TMP/r.json" \
  -- "$PROG" "$MESH" "$PASSES") || exit 1
cmp -s "$TMP/out" "$TMP/native.out" || echo "valgrind_overhead: output differs under emm run!"
accesses=$(captured "$TMP/r.json")
nophases=$(median3 "$EMM" run --capture valgrind --compare baselines --no-phases --tag "$TAG" \
  -- "$PROG" "$MESH" "$PASSES") || exit 1
thesis=$(median3 "$EMM" run --capture valgrind --compare baselines --no-phases --finalists 0 \
  --tag "$TAG" -- "$PROG" "$MESH" "$PASSES") || exit 1
untagged=$(median3 "$EMM" run --capture valgrind -- "$PROG" "$MESH" "$PASSES") || exit 1
none=$(median3 valgrind --tool=none "$PROG" "$MESH" "$PASSES") || exit 1
sancov=$(median3 "$EMM" run --capture sancov --compare baselines --tag "$TAG" -- "$SANCOV" "$MESH" \
  "$PASSES") || exit 1
cg=$(median3 valgrind --tool=cachegrind --cachegrind-out-file=/dev/null "$PROG" "$MESH" "$PASSES") ||
  exit 1
lackey=-
[ -n "$SMOOTH_ONLY" ] ||
  lackey=$(median3 valgrind --tool=lackey --trace-mem=yes --log-file=/dev/null "$PROG" "$MESH" "$PASSES") ||
  exit 1

ratio() { awk -v a="$1" -v b="$native" 'BEGIN { printf "%.1fx", a / b }'; }
echo "smooth on $FACES faces, $PASSES passes; median of 3 wall times; ${accesses:-?} element accesses captured"
printf '  %-44s %8s s\n' "native" "$native"
printf '  %-44s %8s s  %8s\n' "emm run --capture valgrind --compare baselines" "$emm" "$(ratio "$emm")"
printf '  %-44s %8s s  %8s\n' "  the same, --no-phases" "$nophases" "$(ratio "$nophases")"
printf '  %-44s %8s s  %8s\n' "  the thesis: --no-phases --finalists 0" "$thesis" "$(ratio "$thesis")"
printf '  %-44s %8s s  %8s\n' "  the same, nothing tagged (the tool alone)" "$untagged" "$(ratio "$untagged")"
printf '  %-44s %8s s  %8s\n' "  valgrind --tool=none" "$none" "$(ratio "$none")"
printf '  %-44s %8s s  %8s\n' "  the sancov build under emm run (native)" "$sancov" "$(ratio "$sancov")"
printf '  %-44s %8s s  %8s\n' "valgrind --tool=cachegrind" "$cg" "$(ratio "$cg")"
[ -n "$SMOOTH_ONLY" ] ||
  printf '  %-44s %8s s  %8s\n' "valgrind --tool=lackey --trace-mem=yes" "$lackey" "$(ratio "$lackey")"
awk -v e="$emm" -v c="$cg" 'BEGIN { printf "  emm over Cachegrind: %.2fx (target: at most 1x)\n", e / c }'
awk -v n="$nophases" -v t="$thesis" -v c="$cg" \
  'BEGIN { printf "  over Cachegrind: %.2fx with --no-phases, %.2fx with the thesis method\n", n / c, t / c }'
awk -v s="$sancov" -v c="$cg" \
  'BEGIN { printf "  the sancov build under emm run over Cachegrind: %.2fx (target: at most 0.5x)\n", s / c }'

# 2. A real program.
[ -z "$SMOOTH_ONLY" ] || exit 0
DEC=$(command -v OpenMesh-commandlineDecimater) || DEC=
BUNNY=/usr/share/glmark2/models/bunny.obj
if [ -z "$DEC" ] || [ ! -r "$BUNNY" ]; then
  echo "OpenMesh-commandlineDecimater or $BUNNY is not installed: the real program is skipped"
  exit 0
fi
RULE='vertices:site=add_vertex,stride=12,xyz=0:f32'
dec() { "$@" -M Q -n 0.5 -i "$BUNNY" -o "$TMP/dec.obj"; }
native=$(median3 dec "$DEC") || exit 1
cp "$TMP/dec.obj" "$TMP/dec.native.obj"
emm=$(median3 dec "$EMM" run --capture valgrind --compare baselines --tag "$RULE" \
  --report "$TMP/d.json" -- "$DEC") || exit 1
cmp -s "$TMP/dec.obj" "$TMP/dec.native.obj" || echo "valgrind_overhead: the decimated mesh differs under emm run!"
accesses=$(captured "$TMP/d.json")
none=$(median3 dec valgrind --tool=none "$DEC") || exit 1
cg=$(median3 dec valgrind --tool=cachegrind --cachegrind-out-file=/dev/null "$DEC") || exit 1
echo "OpenMesh-commandlineDecimater -M Q -n 0.5 on the bunny; median of 3 wall times; ${accesses:-?} element accesses captured"
printf '  %-44s %8s s\n' "native" "$native"
printf '  %-44s %8s s  %8s\n' "emm run --capture valgrind --compare baselines" "$emm" "$(ratio "$emm")"
printf '  %-44s %8s s  %8s\n' "  valgrind --tool=none" "$none" "$(ratio "$none")"
printf '  %-44s %8s s  %8s\n' "valgrind --tool=cachegrind" "$cg" "$(ratio "$cg")"
awk -v e="$emm" -v c="$cg" 'BEGIN { printf "  emm over Cachegrind: %.2fx (target: at most 1x)\n", e / c }'
