#!/bin/sh
# The acceptance test: 'emm trace import --din' of a Dinero IV address trace,
# then 'emm replay --strategy cache --json', gives exactly the counts of
# Dinero IV's rules (docs/dinero.md) as computed by the separate reference
# model in din_ref, for -dfetch m (the default), d and a.
# usage: din_import_test.sh EMM DIN_REF WORKDIR
set -u
EMM=$1
DINREF=$2
W=$3
rm -rf "$W" && mkdir -p "$W" || exit 1
fail=0
"$DINREF" --generate 50000 11 >"$W/t.din" || exit 1
"$EMM" trace import --din "$W/t.din" -o "$W/t.emmt" || { echo "FAIL: import"; exit 1; }
for f in miss demand always; do
    c=$(echo $f | cut -c1)
    "$DINREF" "$W/t.din" --fetch "$c" >"$W/ref.$f" || exit 1
    "$EMM" replay "$W/t.emmt" --strategy cache --set cache.fetch=$f --json "$W/r.$f.json" --quiet ||
        { echo "FAIL: replay $f"; fail=1; continue; }
    for k in demand_fetches demand_misses prefetch_fetches; do
        v=$(grep "^$k " "$W/ref.$f" | cut -d' ' -f2)
        if grep -q "\"$k\": $v," "$W/r.$f.json"; then
            echo "$f $k $v ok"
        else
            echo "FAIL: $f: $k: reference $v, report: $(grep "\"$k\"" "$W/r.$f.json")"
            fail=1
        fi
    done
done
exit $fail
