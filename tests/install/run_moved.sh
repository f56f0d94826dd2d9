#!/bin/sh
# Runs PROGRAM [ARGS...] under the moved install's `emm run` with nothing in
# the environment (env -i: no PATH, no LD_LIBRARY_PATH, no EMM_*), and
# checks that the program's output is its native run's and that emm decided
# with the shipped table (a pattern matched, an answer given).
# Usage: run_moved.sh PREFIX WORK_DIR NAME [EMM_RUN_OPTIONS... --] PROGRAM [ARGS...]
set -eu
prefix=$1 work=$2 name=$3
shift 3
opts=
case " $* " in
  *" -- "*)
    while [ "$1" != -- ]; do opts="$opts $1"; shift; done
    shift ;;
esac
fail() { echo "FAIL: $*" >&2; exit 1; }
mkdir -p "$work"
env -i "$@" > "$work/$name.native.out"
# shellcheck disable=SC2086
env -i "$prefix/bin/emm" run $opts --report "$work/$name.json" -- "$@" \
  > "$work/$name.out" 2> "$work/$name.err" || { cat "$work/$name.err" >&2; fail "$name: emm run failed"; }
cat "$work/$name.err"
cmp -s "$work/$name.native.out" "$work/$name.out" || fail "$name: output differs under emm run"
grep -q "emm: .*: pattern " "$work/$name.err" || fail "$name: no pattern was matched"
grep -q "emm: answer: " "$work/$name.err" || fail "$name: no answer"
[ -s "$work/$name.json" ] || fail "$name: no report"
