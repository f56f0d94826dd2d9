#!/bin/sh
# A program nobody here wrote, as a user meets emm with it:
#   sh run.sh EMM CAPTURE WORK CASE
# CASE is qdelaunay (qhull-bin), tetgen, mconvert (OpenMesh's converter,
# libopenmesh-apps) or meshio (a Python program on python3-meshio and numpy,
# meshio_normals.py beside this script). The case's program runs natively;
# then `emm run --list-sites` lists its arrays, and the listing's first
# suggested rule, used exactly as printed, tags them in a run under CAPTURE.
# That run's output files and exit status must be the native run's, the rule
# must select the block it was listed for (its size, from --verbose), and the
# report must hold an answer: a strategy and a window of element reads.
# A program that is not installed skips the test (77) with one line.
set -u
EMM=$1 CAPTURE=$2 WORK=$3 CASE=$4
HERE=$(cd "$(dirname "$0")" && pwd)
fail() { echo "FAIL: $CASE: $*" >&2; exit 1; }
skip() { echo "skipped: $*"; exit 77; }
rm -rf "$WORK" && mkdir -p "$WORK/native" "$WORK/emm" "$WORK/list" || fail "cannot make $WORK"
cd "$WORK" || fail "cannot enter $WORK"
PY=/usr/bin/python3

# The input: a generated planar mesh, in the program's format: 8,000 faces
# (4,064 vertices: a 97,536-byte block of f64 points, listed from 64 KiB),
# 20,000 for OpenMesh, whose points are f32.
faces=8000
[ "$CASE" = mconvert ] && faces=20000
"$EMM" mesh gen --faces $faces --seed 3 -o mesh.off > /dev/null || fail "emm mesh gen failed"
STDIN=/dev/null
STDOUT_SAME=yes # no for a program that prints its timings
LIST_CAPTURE=   # the listing's capture: emm run's auto, valgrind for these programs
case $CASE in
qdelaunay)
  command -v qdelaunay > /dev/null || skip "qdelaunay is not installed (Debian: qhull-bin)"
  # qhull's input: the dimension, the count, then the points.
  awk 'NR == 2 { n = $1; print 2; print n } NR > 2 && NR <= 2 + n { print $1, $2 }' mesh.off > points.txt
  STDIN=$WORK/points.txt
  set -- qdelaunay i TO delaunay.txt ;;
tetgen)
  command -v tetgen > /dev/null || skip "tetgen is not installed (Debian: tetgen)"
  # The mesh's vertices lifted onto a paraboloid, as a .node file.
  awk 'NR == 2 { n = $1; print n, 3, 0, 0 }
       NR > 2 && NR <= 2 + n { print NR - 3, $1, $2, ($1 * $1 + $2 * $2) * 0.3 }' mesh.off > points.node
  set -- tetgen -Q points.node ;;
mconvert)
  command -v OpenMesh-mconvert > /dev/null || skip "OpenMesh-mconvert is not installed (Debian: libopenmesh-apps)"
  STDOUT_SAME=no
  set -- OpenMesh-mconvert -i ../mesh.off -o mesh.obj ;;
meshio)
  "$PY" -c 'import meshio, numpy' 2> /dev/null || skip "meshio or numpy is missing for $PY (Debian: python3-meshio)"
  # Listed under the fault capture (records guessed from the bytes):
  # under valgrind numpy's import alone takes some 20 s.
  LIST_CAPTURE="--capture fault"
  set -- "$PY" "$HERE/meshio_normals.py" ../mesh.off mesh.off ;;
*) fail "unknown case" ;;
esac
[ "$CASE" = tetgen ] && for d in native emm list; do cp points.node $d/; done

# Each run works in a directory of its own (native, list, emm), where the
# program writes its output files; the input is in the one above.
(cd native && env -u LD_PRELOAD "$@" < "$STDIN" > stdout 2> stderr)
native_rc=$?
(cd list && "$EMM" run --list-sites $LIST_CAPTURE -- "$@" < "$STDIN" > /dev/null 2> ../listing.txt)
# The first rule listed (a site whose records fit no rule says "rule: none").
site=$(sed -n 's/^emm:  *\([0-9]*\)\. .*/\1/p; /^emm:  *rule: \(vertices\|triangles\|soup\):/q' listing.txt | tail -1)
rule=$(sed -n 's/^emm:  *rule: \(\(vertices\|triangles\|soup\):.*\)/\1/p' listing.txt | head -1)
size=$(sed -n "s/^emm:  *$site\\. .*the largest \\([0-9,]*\\) bytes.*/\\1/p" listing.txt | tr -d ,)
[ -n "$rule" ] || { cat listing.txt >&2; fail "the listing suggests no rule"; }
case $rule in *BYTES* | *OFFSET* | *", or "*) cat listing.txt >&2; fail "the first suggestion is not a rule to use as printed: $rule" ;; esac
echo "$CASE: the listing's first suggestion: $rule (a block of $size bytes)"

(cd emm && "$EMM" run --capture "$CAPTURE" --verbose --tag "$rule" --report "$WORK/report.json" -- \
  "$@" < "$STDIN" > stdout 2> ../emm.err)
rc=$?
[ "$rc" = "$native_rc" ] || { tail -20 emm.err >&2; fail "exit status $rc under emm run, $native_rc natively"; }
[ "$STDOUT_SAME" = no ] || cmp native/stdout emm/stdout || fail "standard output differs from the native run's"
n=0
for f in native/*; do
  case $f in native/stdout | native/stderr) continue ;; esac
  cmp "$f" "emm/${f#native/}" || fail "$(basename "$f") differs from the native run's"
  n=$((n + 1))
done
[ "$n" -gt 0 ] || [ -s native/stdout ] || fail "the native run wrote nothing to compare"
grep -q "EMM_TAG rule 1 selected a block of $size bytes" emm.err ||
  { grep 'EMM_TAG\|tagged' emm.err >&2; fail "the rule did not select the listed block of $size bytes"; }
[ -s report.json ] || { tail -20 emm.err >&2; fail "no report"; }
"$PY" - report.json "$CASE" <<'PY' || { grep '^emm: ' emm.err | grep -v 'EMM_TAG\|tagged' | tail -20 >&2; exit 1; }
import json, sys
r = json.load(open(sys.argv[1]))
w = r['window']
if not w['reads']:
    sys.exit("FAIL: %s: the window holds no element read (%d writes)" % (sys.argv[2], w['writes']))
if r['strategy'] is None:
    sys.exit("FAIL: %s: no answer (report strategy is null)" % sys.argv[2])
print("%s: %d window reads, %s accesses simulated (%s), answer %s" % (
    sys.argv[2], w['reads'], r['coverage']['accesses'], r['coverage']['simulated'], r['strategy']))
PY
grep '^emm: ' emm.err | grep -v 'EMM_TAG\|tagged\|untagged' | head -4
