#!/bin/sh
# emm replay --all speed: the standard sweep (50 strategies) on a
# 1,000,000-access trace over the default 20,000-face generated mesh, on
# all online CPUs; the median of 3 runs, beside a single `--strategy cache`
# replay of the same trace and a `--jobs 1` sweep. Target: under 20 s on a
# 2-core machine. Not a test: run by hand.
# usage: bench/replay_all.sh BUILD_DIR [WORK_DIR]
set -eu
BUILD=${1:?usage: replay_all.sh BUILD_DIR [WORK_DIR]}
EMM=$BUILD/bin/emm
W=${2:-${TMPDIR:-/tmp}/emm-replay-all.$$}
mkdir -p "$W"
[ -n "${2:-}" ] || trap 'rm -rf "$W"' EXIT

now() { date +%s.%N; }
# median3 CMD...: runs CMD three times, prints the median wall time in seconds
median3() {
    for k in 1 2 3; do
        t0=$(now)
        "$@" >/dev/null
        t1=$(now)
        echo "$t0 $t1" | awk '{ printf "%.3f\n", $2 - $1 }'
    done | sort -n | sed -n 2p
}

"$EMM" mesh gen -o "$W/mesh.off" >/dev/null
# Only curves revisit triangles, so only they reach 1,000,000 accesses
# (250,000 visits of 4 records) on 20,000 faces: short curves (thesis §4.3,
# 50 triangles a walk) and long ones (to the boundary).
"$EMM" trace synth --mesh "$W/mesh.off" --pattern curve --length 50 --visits 250000 \
    --work 10 -o "$W/short.emmt"
"$EMM" trace synth --mesh "$W/mesh.off" --pattern curve --visits 250000 --work 10 \
    -o "$W/long.emmt"
echo "cpus online: $(getconf _NPROCESSORS_ONLN)"
for t in short long; do
    all=$(median3 "$EMM" replay "$W/$t.emmt" --all --quiet)
    one=$(median3 "$EMM" replay "$W/$t.emmt" --all --quiet --jobs 1)
    cache=$(median3 "$EMM" replay "$W/$t.emmt" --strategy cache --quiet)
    echo "$t curves, 1000000 accesses: replay --all ${all} s (--jobs 1: ${one} s), " \
         "--strategy cache ${cache} s" |
        awk -v a="$all" -v c="$cache" -v o="$one" \
            '{ printf "%s; --all / cache = %.1f, speed-up of the threads %.2fx\n", $0, a / c, o / a }'
done
