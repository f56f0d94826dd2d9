#!/bin/sh
# The layering check must fail on an upward include: a copy of the tree's
# layer folders with one simulator file that includes a runtime header.
set -eu
src=${1:?usage: detects.sh SOURCE_DIR}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for d in include core simulator runtime shim tools; do
  cp -R "$src/$d" "$work/$d"
done
sh "$src/tests/layering/check.sh" "$work" >/dev/null || { echo "the clean copy fails"; exit 1; }
printf '#include "emm/session.h"\n' >> "$work/simulator/dma.c"
if out=$(sh "$src/tests/layering/check.sh" "$work"); then
  echo "an upward include went unnoticed"; exit 1
fi
echo "$out" | grep -q 'simulator/dma.c:.*emm/session.h.*runtime, above simulator' ||
  { echo "unexpected message: $out"; exit 1; }
printf '#include "lead_sweep.h"\n' > "$work/core/bad.c"
if out=$(sh "$src/tests/layering/check.sh" "$work"); then
  echo "an upward internal include went unnoticed"; exit 1
fi
echo "$out" | grep -q 'core/bad.c:1: includes "lead_sweep.h", a header of runtime, above core' ||
  { echo "unexpected message: $out"; exit 1; }
echo "layering check detects upward includes"
