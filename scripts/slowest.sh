#!/bin/sh
# The slowest entries of the last ctest run in BUILD, slowest first, with
# their times (from BUILD/Testing/Temporary/LastTest.log), so a log shows
# where a run's time went. A missing or unreadable log is a note, not a
# failure: this reports on a run, it is not part of it.
#   scripts/slowest.sh BUILD [N]     (N defaults to 10)
build=${1:?usage: scripts/slowest.sh BUILD [N]}
n=${2:-10}
log=$build/Testing/Temporary/LastTest.log
if [ ! -r "$log" ]; then
  echo "slowest: no test log at $log"
  exit 0
fi
# An entry runs from "k/N Test: NAME" to '"NAME" end time:'; its time is the
# "Test time =" line in between that comes after the test's own output.
out=$(awk '
  /^[0-9]+\/[0-9]+ Test: / { name = $0; sub(/^[0-9]+\/[0-9]+ Test: /, "", name); t = ""; failed = 0 }
  /^Test time = +[0-9.]+ sec$/ { t = $4 }
  /^Test Failed\.$/ { failed = 1 }
  /^".*" end time: / && name != "" && t != "" {
    printf "%10.2f s  %s%s\n", t, name, failed ? "  (failed)" : ""
    name = ""
  }
' "$log" | sort -rn | head -n "$n")
if [ -n "$out" ]; then
  echo "The slowest tests of the last run ($log):"
  printf '%s\n' "$out"
else
  echo "slowest: no test times in $log"
fi
exit 0
