# A loader at scale under the fault capture (tests/shim/bigbuild.c: 2.25 M
# vertices and 4.5 M triangles, 81 MB, built in 0.15 s natively): until the
# first read its writes fault once a page, not once a write (it took 294 s,
# two thousand times its native time, when every write single-stepped). Its
# stdout and exit status are the native run's; the summary counts the
# loader's writes a page at a time (fewer than 100,000, not 9 M): that count,
# not a time, is the check, so that a loaded machine cannot fail it. The
# times are printed for the log; bench/ measures them.
#   sh bigbuild.sh SHIM WORK PROGRAM
. "$(dirname "$0")/lib.sh"
EMM_CAPTURE=fault EMM_LOG=1
EMM_TAG='vertices:site=build_mesh,stride=12,xyz=0:f32;triangles:site=build_mesh,stride=12,vidx=0:u32'
export EMM_CAPTURE EMM_LOG EMM_TAG
t0=$(date +%s%N)
env -u LD_PRELOAD "$@" > /dev/null
t1=$(date +%s%N)
run_both bigbuild "$@"
t2=$(date +%s%N)
native=$(( (t1 - t0) / 1000000 )) fault=$(( (t2 - t1) / 1000000 - native ))
[ "$native" -ge 100 ] || native=100 # a floor for a machine faster than this one
echo "bigbuild: native ${native} ms, under fault capture ${fault} ms ($(( fault / native ))x)"
writes=$(sed -n 's/^emm:   before it, \([0-9,]*\) writes while the mesh was being built.*/\1/p' "$WORK/bigbuild.shim.err" | tr -d ,)
[ -n "$writes" ] || { cat "$WORK/bigbuild.shim.err" >&2; fail "no line counts the loader's writes"; }
[ "$writes" -lt 100000 ] || fail "$writes loader writes seen: one a write, not one a page"
echo "bigbuild: ok ($writes loader writes seen)"
