#!/bin/sh
# replay.sh HARNESS DIR...: runs every file of the DIRs through the harness
# once, with the limits `make fuzz` uses (scripts/fuzz.sh); fails on the
# first crash, hang (-timeout) or memory blow-up (-rss_limit_mb). A missing
# DIR is no error (a harness may have no regression files yet).
set -eu
harness=$1; shift
files=$(for d in "$@"; do [ -d "$d" ] && find "$d" -type f ! -name README.md; done | sort)
[ -n "$files" ] || { echo "replay: no inputs in $*" >&2; exit 1; }
n=$(echo "$files" | wc -l)
# shellcheck disable=SC2086
"$harness" -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=256 $files > /dev/null 2> "${TMPDIR:-/tmp}/replay.$$" || {
  tail -40 "${TMPDIR:-/tmp}/replay.$$" >&2; rm -f "${TMPDIR:-/tmp}/replay.$$"; exit 1; }
rm -f "${TMPDIR:-/tmp}/replay.$$"
echo "replay: $(basename "$harness"): $n inputs, no crash, hang or memory blow-up"
