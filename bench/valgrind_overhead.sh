#!/bin/sh
# The valgrind capture's cost (issue 14's benchmark; not a test: it times
# things).
#
#   sh bench/valgrind_overhead.sh [--smooth-only] BUILD [FACES] [PASSES] [ROUNDS]
#
# --smooth-only: the smoothing program's rows without Lackey, and not the
# decimater (minutes instead of an hour on a busy machine: Lackey alone
# takes about 4,000 times the native run).
#
# Two programs, each with one input, in one run; wall times, median of 3,
# as ratios over the program's native run. The two targets are paired: emm
# (the defaults), the sancov build and Cachegrind run in turn, in a
# different order each round, for ROUNDS rounds (default 5), and each
# target is the median of the rounds' own ratios — the machine's drift
# (a shared machine slows and speeds up over a minute) then falls on both
# sides of a ratio alike.
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
[ $# -ge 1 ] || { echo "usage: sh bench/valgrind_overhead.sh [--smooth-only] BUILD [FACES] [PASSES] [ROUNDS]" >&2; exit 2; }
B=$(cd "$1" && pwd) || exit 1
FACES=${2:-100000} PASSES=${3:-10} ROUNDS=${4:-5}
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
# once CMD...: the wall time of one run, in nanoseconds.
once() {
  t0=$(now)
  "$@" > "$TMP/out" 2> "$TMP/err" || { cat "$TMP/err" >&2; echo "valgrind_overhead: $* failed" >&2; exit 1; }
  echo $(( $(now) - t0 ))
}
# median3 CMD...: the median wall time of three runs, in seconds.
median3() {
  for i in 1 2 3; do
    once "$@" || exit 1
  done | sort -n | sed -n 2p | awk '{ printf "%.3f\n", $1 / 1e9 }'
}
# median FILE: the median of the numbers in FILE, one a line.
median() {
  sort -g "$1" | awk '{ v[NR] = $1 } END { printf "%.3f\n", NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'
}

native=$(median3 "$PROG" "$MESH" "$PASSES") || exit 1
cp "$TMP/out" "$TMP/native.out"
# The paired rounds: emm (the defaults), the sancov build, Cachegrind.
run_emm() {
  once "$EMM" run --capture valgrind --compare baselines --tag "$TAG" --report "$TMP/r.json" \
    -- "$PROG" "$MESH" "$PASSES" > "$TMP/t.emm" || exit 1
  cmp -s "$TMP/out" "$TMP/native.out" || echo "valgrind_overhead: output differs under emm run!" >&2
}
run_sancov() {
  once "$EMM" run --capture sancov --compare baselines --tag "$TAG" -- "$SANCOV" "$MESH" "$PASSES" \
    > "$TMP/t.sancov" || exit 1
}
run_cg() {
  once valgrind --tool=cachegrind --cachegrind-out-file=/dev/null "$PROG" "$MESH" "$PASSES" \
    > "$TMP/t.cg" || exit 1
}
: > "$TMP/emm.all"; : > "$TMP/sancov.all"; : > "$TMP/cg.all"; : > "$TMP/emm.ratio"; : > "$TMP/sancov.ratio"
r=0
while [ $r -lt "$ROUNDS" ]; do
  case $((r % 3)) in
    0) run_emm; run_sancov; run_cg ;;
    1) run_cg; run_emm; run_sancov ;;
    2) run_sancov; run_cg; run_emm ;;
  esac
  e=$(cat "$TMP/t.emm") sc=$(cat "$TMP/t.sancov") c=$(cat "$TMP/t.cg")
  awk -v a="$e" 'BEGIN { print a / 1e9 }' >> "$TMP/emm.all"
  awk -v a="$sc" 'BEGIN { print a / 1e9 }' >> "$TMP/sancov.all"
  awk -v a="$c" 'BEGIN { print a / 1e9 }' >> "$TMP/cg.all"
  awk -v a="$e" -v b="$c" 'BEGIN { print a / b }' >> "$TMP/emm.ratio"
  awk -v a="$sc" -v b="$c" 'BEGIN { print a / b }' >> "$TMP/sancov.ratio"
  r=$((r + 1))
done
emm=$(median "$TMP/emm.all") sancov=$(median "$TMP/sancov.all") cg=$(median "$TMP/cg.all")
emm_cg=$(median "$TMP/emm.ratio") sancov_cg=$(median "$TMP/sancov.ratio")
accesses=$(captured "$TMP/r.json")
nophases=$(median3 "$EMM" run --capture valgrind --compare baselines --no-phases --tag "$TAG" \
  -- "$PROG" "$MESH" "$PASSES") || exit 1
thesis=$(median3 "$EMM" run --capture valgrind --compare baselines --no-phases --finalists 0 \
  --tag "$TAG" -- "$PROG" "$MESH" "$PASSES") || exit 1
untagged=$(median3 "$EMM" run --capture valgrind -- "$PROG" "$MESH" "$PASSES") || exit 1
none=$(median3 valgrind --tool=none "$PROG" "$MESH" "$PASSES") || exit 1
lackey=-
[ -n "$SMOOTH_ONLY" ] ||
  lackey=$(median3 valgrind --tool=lackey --trace-mem=yes --log-file=/dev/null "$PROG" "$MESH" "$PASSES") ||
  exit 1

ratio() { awk -v a="$1" -v b="$native" 'BEGIN { printf "%.1fx", a / b }'; }
echo "smooth on $FACES faces, $PASSES passes; median wall times (of $ROUNDS paired rounds for emm, sancov and Cachegrind, else of 3); ${accesses:-?} element accesses captured"
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
echo "  emm over Cachegrind: ${emm_cg}x, the median of $ROUNDS paired rounds' ratios (target: at most 1x)"
awk -v n="$nophases" -v t="$thesis" -v c="$cg" \
  'BEGIN { printf "  over Cachegrind: %.2fx with --no-phases, %.2fx with the thesis method\n", n / c, t / c }'
echo "  the sancov build under emm run over Cachegrind: ${sancov_cg}x, the median of $ROUNDS paired rounds' ratios (target: at most 0.5x)"

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
