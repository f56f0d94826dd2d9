#!/bin/sh
# emm profile and emm table as a user runs them: exit statuses, messages,
# the JSON keys and the CSV columns. Arguments: the emm binary, the
# make_trace helper, a scratch directory.
set -u
EMM=$1 MAKE=$2 DIR=$3
rm -rf "$DIR" && mkdir -p "$DIR" && cd "$DIR" || exit 1
fail=0
check() { # check NAME EXPECTED-STATUS COMMAND...
    name=$1 want=$2; shift 2
    "$@" >out.txt 2>err.txt; got=$?
    if [ "$got" != "$want" ]; then
        echo "FAIL $name: exit $got, wanted $want"; cat out.txt err.txt; fail=1
    fi
}
has() { # has NAME FILE TEXT
    if ! grep -q -- "$3" "$2"; then echo "FAIL $1: '$3' not in $2:"; cat "$2"; fail=1; fi
}
record() { # record TRACE MESH PROGRAM [ARG]: PROGRAM [ARG] MESH under emm run's sancov capture
    trace=$1 mesh=$2; shift 2
    "$EMM" run --quiet --capture sancov --trace "$trace" -- "$@" "$mesh" >/dev/null
}
near_best() { # near_best NAME TRACE PERCENT: out.txt's strategy within PERCENT % of the
    # fewest cycles of emm replay --all over TRACE (the cache aside: no candidate)
    predicted=$(sed -n 's/^strategy: *//p' out.txt)
    check "$1-all" 0 "$EMM" replay "$2" --all
    best=$(awk '$1 ~ /^[0-9]+$/ && $2 !~ /^cache/ { print $3; exit }' out.txt)
    mine=$(awk -v s="$predicted" '$1 ~ /^[0-9]+$/ && $2 == s { print $3; exit }' out.txt)
    if [ -z "$best" ] || [ -z "$mine" ] || [ $((mine * 100)) -gt $((best * (100 + $3))) ]; then
        echo "FAIL $1: predicted $predicted ($mine cycles), the run's best $best cycles"
        fail=1
    fi
}

"$MAKE" grid grid.emmt && "$MAKE" walk walk.emmt && "$MAKE" raw raw.emmt || exit 1
unset EMM_TABLE

check help-profile 0 "$EMM" profile --help
has help-profile out.txt "usage: emm profile TRACE"
check help-table 0 "$EMM" table --help
check help-table-add 0 "$EMM" table add --help
has help-table-add out.txt "the best of the standard sweep"
has help-table-add out.txt "emm table build"
check no-trace 2 "$EMM" profile
has no-trace err.txt "emm profile: missing TRACE"
check bad-window 2 "$EMM" profile grid.emmt --window ten
check small-window 2 "$EMM" profile grid.emmt --window 10
check bad-option 2 "$EMM" profile grid.emmt --fast
check missing 1 "$EMM" profile nosuch.emmt
check raw 1 "$EMM" profile raw.emmt
has raw err.txt "raw.emmt: an address-only trace"
check table-bad-sub 2 "$EMM" table frob
check table-add-bad-strategy 2 "$EMM" table add grid.emmt --name g --strategy warp --table user.txt
check table-add-no-table 2 "$EMM" table add grid.emmt --name g --strategy cache

# Without any table: a clear message naming the default path.
default=$("$EMM" profile --help | sed -n 's/^The default table is \(.*\)\.$/\1/p')
if [ ! -e "$default" ]; then
    check no-table 1 "$EMM" profile grid.emmt --dump nt.csv
    has no-table err.txt "no strategy table found: tried $default"
    has no-table-dump nt.csv "^i,D$"
fi

# Build a user table from the two traces, list it, profile against it.
check add-grid 0 "$EMM" table add grid.emmt --name rows --pattern scanline --strategy tiles+extrapolated@64 --table user.txt
check add-walk 0 "$EMM" table add walk.emmt --name shuffled --pattern walk --strategy cache --table user.txt
check add-dup 1 "$EMM" table add walk.emmt --name rows --strategy cache --table user.txt
has add-dup err.txt "already in this table"
check list 0 "$EMM" table list --table user.txt
has list out.txt "rows .*scanline .*tiles+extrapolated@64"
has list out.txt "shuffled .*walk .*cache .*user.txt:"
EMM_TABLE=user.txt check list-env 0 "$EMM" table list
has list-env out.txt "shuffled"

check profile 0 "$EMM" profile walk.emmt --table user.txt --dump walk.csv --json walk.json
has profile out.txt "pattern: *walk"
has profile out.txt "nearest: *shuffled (distance 0.0000)"
# The sample (class walk: no canonical traversal to check it by) says the
# cache; the default machine has none, so the window's candidates decide ...
if grep -q "strategy: *cache" out.txt; then echo "FAIL profile: chose the cache on a machine without one"; fail=1; fi
has profile out.txt "simulated: .* strategies on the window"
has profile out.txt "novel: *no"
for key in pattern strategy nearest distance novel; do has json walk.json "\"$key\""; done
# ... and a machine that declares its cache takes the sample's answer (the
# window's prediction: --finalists 0 holds no contest over the trace).
check profile-cache 0 "$EMM" profile walk.emmt --table user.txt --set cache.present=1 --finalists 0
has profile-cache out.txt "strategy: *cache$"
# The contest over the whole trace (the default): the prediction, the
# candidates, the answer and its cycles, and the prediction's against it.
check profile-contest 0 "$EMM" profile walk.emmt --table user.txt --set cache.present=1 --json walk.json
has profile-contest out.txt "^predicted: *cache$"
# Every strategy of the standard sweep (as many as emm replay --help says).
sweep=$("$EMM" replay --help | sed -n 's/.*: \([0-9][0-9]*\) strategies,*$/\1/p')
[ -n "$sweep" ] || { echo "FAIL profile-contest: emm replay --help does not say the sweep's size"; fail=1; }
has profile-contest out.txt "^contest: *$sweep candidates over the whole trace"
has profile-contest out.txt "^strategy: "
has profile-contest out.txt "^predicted: cache, [0-9]* cycles over the trace, [0-9.]*x the answer$"
has json walk.json '"predicted": "cache"'
check bad-finalists 2 "$EMM" profile walk.emmt --finalists 65
has bad-finalists err.txt "finalists"
# --finalists all: none is dropped, so the answer is the fewest cycles of
# every candidate over the trace, as emm replay --all counts them.
check profile-all 0 "$EMM" profile walk.emmt --table user.txt --set cache.present=1 --finalists all
has profile-all out.txt "^contest: *$sweep candidates over the whole trace (.*), every one run$"
answer=$(sed -n 's/^run: *\([^ ]*\) \([0-9]*\) cycles$/\1 \2/p' out.txt)
"$EMM" replay walk.emmt --all --set cache.present=1 --json all.json --quiet || fail=1
best=$(python3 -c "
import json
r = [x for x in json.load(open('all.json'))['results'] if 'cycles' in x]
print(min(x['cycles']['total'] for x in r))")
[ "${answer#* }" = "$best" ] || { echo "FAIL profile-all: answer $answer, the fewest cycles of replay --all $best"; fail=1; }
has json walk.json '"pattern": "walk"'
has csv walk.csv "^i,D$"
lines=$(wc -l < walk.csv)
# The default window (16384 element accesses) and the header line.
[ "$lines" -eq 16385 ] || { echo "FAIL csv: $lines lines, wanted 16385"; fail=1; }
check profile-grid 0 "$EMM" profile grid.emmt --table user.txt --window 4096
has profile-grid out.txt "pattern: *scanline"
# Its mesh is larger than the local store, and 4,096 accesses of it fill
# little of the store: the window reads on, to 1.5 times its length.
has profile-grid out.txt "window: *6144 element accesses (exact method): read on past the 4096 asked for"
check profile-novel 0 "$EMM" profile grid.emmt --table user.txt --window 4096 --threshold 1e-9
has profile-novel out.txt "novel: *yes"

# Without --strategy, the best of the sweep simulated on the window.
check add-swept 0 "$EMM" table add grid.emmt --name swept --window 4096 --table swept.txt
has add-swept out.txt "added swept (user, .*: the best of [0-9]* strategies"
has add-swept-file swept.txt "^swept "
check add-swept-bad-set 2 "$EMM" table add grid.emmt --name s2 --table swept.txt --set nosuch.key=1

# A novel profile: the sweep decides, and --learn adds it to the user table.
check simulate 0 "$EMM" profile walk.emmt --table user.txt --simulate --json sim.json
has simulate out.txt "simulated: [0-9]* strategies on the window; best [0-9]* cycles"
has simulate-json sim.json '"simulated": true'
check learn-no-table 2 "$EMM" profile walk.emmt --learn w1
check learn 0 "$EMM" profile walk.emmt --table learn.txt --threshold 1e-9 --learn w1 --pattern walk
has learn out.txt "novel: *yes"
has learn out.txt "learnt: *w1 (walk, "
has learn-file learn.txt "^w1 *walk "
check learn-again 0 "$EMM" profile walk.emmt --table learn.txt --window 4096
has learn-again out.txt "nearest: *"
# With the contest (the default), --learn adds the run's answer, novel or not:
# the sample's strategy is the one the contest answered.
check learn-contest 0 "$EMM" profile walk.emmt --table learn2.txt --learn w2
has learn-contest out.txt "learnt: *w2 (user, .*, the contest's answer over the run) added"
answer=$(sed -n 's/^strategy: *//p' out.txt)
# ... measured on this machine (its fingerprint), with the answer's cost 1.
has learn-contest-file learn2.txt "^w2 *user *- *[0-9a-f]\{16\} *$answer .* $answer=1"
check learn-none 0 "$EMM" profile walk.emmt --table learn3.txt --finalists 0 --learn w3
has learn-none out.txt "learnt: *nothing"

# The neighbours' costs: a walk over a mesh, recorded under emm run, is far
# from every canonical sample; the table's walks measured on this machine
# decide its prediction. On a machine that differs in one key they are not
# trusted, and the class check decides.
BIN=$(dirname "$EMM")
if [ -x "$BIN/predict_traversals.sancov" ]; then
    "$EMM" mesh gen --faces 4000 --seed 77 -o walk4k.off >/dev/null &&
        record walk4k.emmt walk4k.off "$BIN/predict_traversals.sancov" walk || exit 1
    check costs 0 "$EMM" profile walk4k.emmt --finalists 0
    has costs out.txt "^measured: *the 16 nearest runs measured on this machine"
    check costs-other-machine 0 "$EMM" profile walk4k.emmt --finalists 0 --set local.bytes=128K
    has costs-other-machine out.txt "^checked: "
    if grep -q "^measured:" out.txt; then echo "FAIL costs-other-machine: decided by costs"; fail=1; fi
else
    echo "costs: $BIN/predict_traversals.sancov not built (no clang): not checked"
fi

# The neighbours' best scores are weighed with the checked pattern's run over
# the program's own mesh. A breadth-first flood fill over a 30,000-face torus:
# its front, once it wraps round the tube, outgrows the store for 8-triangle
# cells, which the neighbours (runs on other meshes) and the cold window
# rank first (1.50 times the run's best); the region traversal made over
# the torus ranks the run's best first. The prediction must be within 3 %
# of the fewest cycles of emm replay --all (the cache aside: no candidate).
if [ -x "$BIN/predict_traversals.sancov" ]; then
    "$EMM" mesh gen --surface torus --faces 30000 --seed 45 -o torus30k.off >/dev/null &&
        record flood30k.emmt torus30k.off "$BIN/predict_traversals.sancov" flood || exit 1
    check long-run 0 "$EMM" profile flood30k.emmt --finalists 0
    has long-run out.txt "^measured: *the 16 nearest runs measured on this machine"
    has long-run out.txt "^ *and region.* over this mesh ([0-9]* visits) for the 16 best"
    near_best long-run flood30k.emmt 3
else
    echo "long-run: $BIN/predict_traversals.sancov not built (no clang): not checked"
fi

# A window near a canonical sample is that pattern only when the pattern,
# made on the program's own mesh, resembles the window too. Region growing
# (a one-ring from every vertex) over a 30,000-face mesh once lay 0.33 from
# a spiral sample while the spiral, made over this mesh, lay 0.46 from the
# window: the runs measured on this machine decided, not the check (whose
# long run chose 128-triangle cells, 37 % slower than the run's best). The
# table now holds the region grown over one-rings, which the window lies
# nearest and which, made over this mesh, resembles it: the check decides
# with that traversal, and predicts the run's best.
if [ -x "$BIN/region_growing.sancov" ]; then
    "$EMM" mesh gen --faces 30000 --seed 42 --density uniform -o grow30k.off >/dev/null &&
        record grow30k.emmt grow30k.off "$BIN/region_growing.sancov" || exit 1
    check check-unlike 0 "$EMM" profile grow30k.emmt --finalists 0
    has check-unlike out.txt "^checked: *region@ring over this mesh"
    near_best check-unlike grow30k.emmt 5
else
    echo "check-unlike: $BIN/region_growing.sancov not built (no clang): not checked"
fi

# ... and when the class checked does not resemble the window, another
# canonical class may: a Gray-code traversal's window of 8,192 accesses over
# a 16,000-face clustered mesh lies nearest a Hilbert scan's sample, whose
# traversal made on that mesh lies 0.525 from it, but the Gray-code
# traversal made there lies within 0.35: it is the class checked (the
# neighbours, which decided before, were 9.10 % off the run's best).
"$EMM" mesh gen --faces 16000 --density clustered --seed 22 -o gray16k.off >/dev/null &&
    "$EMM" trace synth --mesh gray16k.off --pattern gray --seed 322 -o gray16k.emmt >/dev/null ||
    { echo "FAIL near-class: cannot make the gray trace"; exit 1; }
check near-class 0 "$EMM" profile gray16k.emmt --window 8192 --finalists 0
has near-class out.txt "^pattern: *gray$"
has near-class out.txt "^checked: *gray over this mesh"

# A leading sweep is the run's too: curve tracing reads every triangle in
# index order before it traces, and on a 10,000-face mesh that sweep is
# about half of the run's cycles. The profile leaves it out; the
# neighbours' score adds its cycles, so the prediction is near the run's
# best (within 6 %; 39 % off when the sweep was not priced: cells that
# serve the curves but make the sweep dear).
if [ -x "$BIN/curve_tracing.sancov" ]; then
    "$EMM" mesh gen --faces 10000 --seed 41 --density clustered -o curves10k.off >/dev/null &&
        record curves10k.emmt curves10k.off "$BIN/curve_tracing.sancov" --short || exit 1
    check lead 0 "$EMM" profile curves10k.emmt --finalists 0
    has lead out.txt "^ *and the leading sweep's [0-9]* records, the run's too"
    predicted=$(sed -n 's/^strategy: *//p' out.txt)
    "$EMM" replay curves10k.emmt --all > all.txt || exit 1
    awk -v p="$predicted" '$1 ~ /^[0-9]+$/ && $2 !~ /^cache/ {
            if (!best) best = $3
            if ($2 == p) mine = $3
        }
        END {
            if (!mine || mine > 1.15 * best) {
                printf "FAIL lead: %s takes %s cycles, the run'"'"'s best %s\n", p, mine, best
                exit 1
            }
        }' all.txt || fail=1
else
    echo "lead: $BIN/curve_tracing.sancov not built (no clang): not checked"
fi

# The pattern check prices the leading sweep too. A Hilbert-order scan
# reads every triangle in index order first; over a randomly numbered mesh
# that sweep jumps across the whole mesh. Without the table's scan-hilbert
# samples (the prediction benchmark's leave-one-program-out, which
# build/bin/predict applies), a 32,768-access window of it lies near a
# canonical Hilbert sample and the check decides: its long run alone
# chose 32-triangle cells, 2.7 times the run's best, which make the sweep
# dear.
if [ -x "$BIN/predict_traversals.sancov" ] && [ -x "$BIN/predict" ]; then
    "$EMM" mesh gen --faces 30000 --seed 42 --density uniform --order random \
        -o hilbert30k.off >/dev/null &&
        record hilbert30k.emmt hilbert30k.off "$BIN/predict_traversals.sancov" scan-hilbert &&
        "$EMM" replay hilbert30k.emmt --all >hilbert30k.all || exit 1
    echo "scan-hilbert hilbert30k hilbert30k.emmt - hilbert30k.all" >cases.txt
    check check-lead 0 "$BIN/predict" cases.txt --window 32768
    awk '$1 == "hilbert30k" {
            found = 1
            if ($3 != "checked") { printf "FAIL check-lead: decided by %s, not the check\n", $3; exit 1 }
            if ($6 + 0 > 15) { printf "FAIL check-lead: %s is %s off the run'"'"'s best\n", $4, $6; exit 1 }
        }
        END { if (!found) { print "FAIL check-lead: no case line"; exit 1 } }' out.txt ||
        { cat out.txt; fail=1; }
else
    echo "check-lead: $BIN/predict_traversals.sancov or $BIN/predict not built: not checked"
fi

# emm table build: deterministic, with a header saying how it was made.
check build-1 0 "$EMM" table build --quick -o built1.txt
has build-1 out.txt "wrote built1.txt: [0-9]* samples"
check build-2 0 "$EMM" table build --quick -o built2.txt
cmp -s built1.txt built2.txt || { echo "FAIL build: two runs differ"; fail=1; }
has build-header built1.txt "^emm-table 4 features=19$"
has build-header built1.txt "Generated by .emm table build --quick."
has build-samples built1.txt "^zorder-6ku-w4096 *zorder "
check build-bad 2 "$EMM" table build --frob

# A broken table is an error naming the file and the line.
printf 'emm-table 2 features=19\nx random cache 1 2 3\n' > broken.txt
check broken 1 "$EMM" profile grid.emmt --table broken.txt
has broken err.txt "broken.txt:2: expected name, pattern, strategy"

[ $fail = 0 ] && echo "cli: all checks passed"
exit $fail
