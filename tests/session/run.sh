#!/bin/sh
# emm run: usage errors, the shim not found (the paths tried are named), the
# environment it sets (a stand-in library placed where the shim belongs, so
# this part does not depend on the shim), LD_PRELOAD prepended, the
# program's exit status and a death by signal passed through; then, when the
# real shim is built, a workload under `emm run` against its native run.
# Usage: run.sh EMM REGION_GROWING WORKDIR
set -u
emm=$1 region=$2 work=$3
rm -rf "$work" && mkdir -p "$work/bin" "$work/lib" || exit 1
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }

"$emm" run --help >"$work/help" 2>&1 || fail "--help exits non-zero"
grep -q 'usage: emm run' "$work/help" || fail "--help prints no usage"
"$emm" run >/dev/null 2>"$work/err"; [ $? -eq 2 ] || fail "no PROGRAM: not 2"
grep -q 'missing PROGRAM' "$work/err" || fail "no PROGRAM: message"
"$emm" run --strategy grid+sideways -- true 2>"$work/err"; [ $? -eq 2 ] || fail "bad strategy: not 2"
grep -q 'grid+sideways' "$work/err" || fail "bad strategy: message"
"$emm" run --profile 0 -- true 2>/dev/null; [ $? -eq 2 ] || fail "--profile 0: not 2"
"$emm" run --profile 5it --compare all --capture fault --bogus x -- true 2>"$work/err"
[ $? -eq 2 ] && grep -q "unknown option '--bogus'" "$work/err" || fail "unknown option"

# A bad option: exit status 2, one line naming the option as typed, and the
# program never starts (configuration table: core/config.c).
printf 'dma.issue = abc\n' > "$work/bad.ini"
for args in "--tag garbage" "--report $work/nodir/x.json" "--machine $work/nosuch.ini" \
            "--machine $work/bad.ini" "--compare bogus" "--capture magic" "--log 7"; do
    opt=${args%% *}
    rm -f "$work/started"
    "$emm" run $args -- sh -c "touch '$work/started'" 2>"$work/err"; rc=$?
    [ $rc -eq 2 ] || fail "$args: exit $rc, not 2"
    [ "$(wc -l < "$work/err")" -eq 1 ] || fail "$args: not one line: $(cat "$work/err")"
    grep -q -- "^emm run: $opt" "$work/err" || fail "$args: the line does not name $opt: $(cat "$work/err")"
    [ ! -e "$work/started" ] || fail "$args: the program started"
done
# A bad variable the options leave alone is refused the same way, by name.
EMM_PROFILE=zz "$emm" run -- true 2>"$work/err"; rc=$?
[ $rc -eq 2 ] && grep -q "^emm run: EMM_PROFILE='zz'" "$work/err" || fail "EMM_PROFILE=zz: exit $rc"

# A copy of emm with nothing beside it: the shim is not found.
cp "$emm" "$work/bin/emm" || exit 1
# (--strategy: a copy outside the build tree has no table to decide with.)
"$work/bin/emm" run --strategy cache -- true 2>"$work/err"; rc=$?
[ $rc -eq 1 ] || fail "shim missing: exit $rc, not 1"
grep -q "cannot find libemmshim.so; tried $work/bin/../lib/libemmshim.so" "$work/err" ||
    { fail "shim missing: message"; cat "$work/err"; }
# Nor is emm's Valgrind tool: --capture valgrind says it is unavailable, in
# one line, before the program starts.
"$work/bin/emm" run --strategy cache --capture valgrind -- true 2>"$work/err"; rc=$?
[ $rc -eq 1 ] || fail "valgrind tool missing: exit $rc, not 1"
grep -q "^emm: run: --capture valgrind is unavailable: emm's Valgrind tool is not beside this emm" \
    "$work/err" || { fail "valgrind tool missing: message"; cat "$work/err"; }

# A stand-in shim: any harmless shared library will do for LD_PRELOAD.
stand=$(ldd "$emm" | awk '/libm\.so/ { print $3; exit }')
[ -n "$stand" ] || stand=$(ldd "$emm" | awk '/libc\.so/ { print $3; exit }')
cp "$stand" "$work/lib/libemmshim.so" || exit 1
# The copy is laid out as an install: its shipped table in share/emm.
mkdir -p "$work/share/emm" &&
    ln -s "$(dirname "$emm")/../share/emm/table.txt" "$work/share/emm/table.txt" || exit 1
shim=$(cd "$work/lib" && pwd -P)/libemmshim.so
LD_PRELOAD= "$work/bin/emm" run --report "$work/r-%p.json" --strategy cache --profile 5it \
    --compare none --quiet -- sh -c 'echo "$LD_PRELOAD|$EMM_REPORT|$EMM_STRATEGY|$EMM_PROFILE|$EMM_COMPARE|$EMM_LOG"; exit 3' \
    >"$work/out" 2>"$work/err"; rc=$?
[ $rc -eq 3 ] || fail "exit status $rc, not 3"
[ "$(cat "$work/out")" = "$shim|$work/r-%p.json|cache|5it|none|0" ] ||
    fail "environment: $(cat "$work/out") (stderr: $(cat "$work/err"))"
LD_PRELOAD=libdl.so.2 "$work/bin/emm" run sh -c 'echo "$LD_PRELOAD"' >"$work/out" 2>"$work/err"
[ "$(cat "$work/out")" = "$shim:libdl.so.2" ] || fail "LD_PRELOAD not prepended: $(cat "$work/out")"
# The stand-in never answers as the shim does when it loads: one line says
# the program ran without emm.
[ "$(cat "$work/err")" = "emm: run: sh ran without emm, nothing captured: the loader did not preload libemmshim.so into it" ] ||
    fail "a shim that did not load: $(cat "$work/err")"
"$work/bin/emm" run -- sh -c 'kill -TERM $$' 2>/dev/null; rc=$?
[ $rc -eq 143 ] || fail "death by SIGTERM: exit $rc, not 143"
"$work/bin/emm" run -- "$work/no-such-program" 2>"$work/err"; rc=$?
[ $rc -eq 127 ] && grep -q 'no-such-program' "$work/err" || fail "missing program: exit $rc"

# The real shim, once it is built beside emm.
bindir=$(dirname "$emm")
if [ -f "$bindir/../lib/libemmshim.so" ] && [ -x "$region" ]; then
    mesh=$work/mesh.off
    "$emm" mesh gen --faces 3000 --seed 2 -o "$mesh" >/dev/null || exit 1
    "$region" "$mesh" >"$work/native.out" 2>/dev/null; native_rc=$?
    "$emm" run --profile 2K --strategy cache --report "$work/run.json" --trace "$work/run.emmt" -- \
        "$region" "$mesh" >"$work/shim.out" 2>"$work/shim.err"; rc=$?
    [ $rc -eq $native_rc ] || fail "workload: exit $rc under emm run, $native_rc native"
    cmp -s "$work/native.out" "$work/shim.out" || fail "workload: output differs under emm run"
    grep -q '"strategy": "cache"' "$work/run.json" 2>/dev/null ||
        { fail "workload: no report"; cat "$work/shim.err"; }
    if [ -f "$work/run.emmt" ]; then
        "$emm" replay "$work/run.emmt" --strategy cache --strategy direct --json "$work/replay.json" \
            --quiet || fail "replay of EMM_TRACE"
        # Every number of every result (all cycle buckets, cache and DMA
        # counters), not only the totals.
        if command -v python3 >/dev/null 2>&1; then
            python3 - "$work/run.json" "$work/replay.json" <<'PY' || fail "replay of EMM_TRACE: results differ"
import json, sys
run, rep = (json.load(open(p)) for p in sys.argv[1:3])
assert run["accesses"] == rep["accesses"] > 0, (run["accesses"], rep["accesses"])
by = {r["strategy"]: r for r in rep["results"]}
assert len(run["results"]) == 2 and sorted(by) == sorted(r["strategy"] for r in run["results"])
for r in run["results"]:
    if r != by[r["strategy"]]:
        sys.exit("%s: run %s, replay %s" % (r["strategy"], r, by[r["strategy"]]))
PY
        else
            a=$(sed -n '/"results"/,/^  \]/p' "$work/run.json" | grep -E '^ *"[a-z_]+": [0-9]' | sort)
            b=$(sed -n '/"results"/,/^  \]/p' "$work/replay.json" | grep -E '^ *"[a-z_]+": [0-9]' | sort)
            [ -n "$a" ] && [ "$a" = "$b" ] || fail "replay of EMM_TRACE: results differ"
        fi
    else
        fail "workload: no EMM_TRACE file"
    fi
else
    echo "note: $bindir/../lib/libemmshim.so not built; the workload part is skipped"
fi

[ $fails -eq 0 ] && echo "all passed"
exit $((fails > 0))
