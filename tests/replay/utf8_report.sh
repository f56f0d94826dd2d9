#!/bin/sh
# A report written for files whose names are not UTF-8 (byte 0xff, as a
# Latin-1 file system would give) is still valid JSON: Python's strict
# json.load reads it, and each bad byte is U+FFFD (docs/report.md). The same
# for emm mesh info --json.
# usage: utf8_report.sh EMM DATA WORKDIR
set -u
EMM=$1 DATA=$2 W=$3
rm -rf "$W" && mkdir -p "$W" || exit 1
fail() { echo "FAIL: $*"; exit 1; }
bad=$(printf 'na\377me')
cp "$DATA/workloads/grid4.off" "$W/$bad.off" || fail "cannot make a file named with byte 0xff"
"$EMM" trace synth --mesh "$W/$bad.off" --pattern region -o "$W/$bad.emmt" > /dev/null || fail "trace synth"
"$EMM" replay "$W/$bad.emmt" --strategy direct --strategy cache --json "$W/report.json" > /dev/null ||
  fail "replay"
"$EMM" mesh info --json "$W/$bad.off" > "$W/info.json" || fail "mesh info"
grep -q "$(printf '\377')" "$W/report.json" "$W/info.json" && fail "a raw 0xff byte in the JSON"
python3 - "$W/report.json" "$W/info.json" <<'PY' || exit 1
import json, sys
report = json.load(open(sys.argv[1], encoding="utf-8"))
info = json.load(open(sys.argv[2], encoding="utf-8"))
assert report["trace"].endswith("na\ufffdme.emmt"), report["trace"]
assert "na\ufffdme.off" in json.dumps(info, ensure_ascii=False), info
print("utf8_report: both parse; 0xff became U+FFFD")
PY
