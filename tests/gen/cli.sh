#!/bin/sh
# Integration tests of 'emm mesh gen' and 'emm mesh info', run as a user would.
# usage: cli.sh EMM WORKDIR MODE   (MODE: determinism | faces | errors | help)
set -u
emm=$1
dir=$2
mode=$3
rm -rf "$dir"
mkdir -p "$dir" || exit 1
failures=0

fail() {
    echo "FAIL: $*" >&2
    failures=$((failures + 1))
}

# field FILE LABEL: the value after "LABEL: " in 'emm mesh info FILE'.
field() {
    "$emm" mesh info "$1" | sed -n "s/^$2: //p"
}

# expect_status CODE CMD...: runs CMD, checks its exit status and that stderr
# is one or two lines (the message, and the usage hint) starting with "emm".
expect_status() {
    want=$1
    shift
    "$@" >"$dir/out" 2>"$dir/err"
    got=$?
    [ "$got" -eq "$want" ] || fail "'$*' exited $got, not $want"
    lines=$(wc -l <"$dir/err")
    [ "$lines" -ge 1 ] && [ "$lines" -le 2 ] || fail "'$*' wrote $lines lines on stderr"
    head -n 1 "$dir/err" | grep -q '^emm' || fail "'$*' stderr does not start with emm: $(cat "$dir/err")"
    [ -s "$dir/out" ] && fail "'$*' wrote on stdout"
    echo "ok: '$*' -> $got: $(head -n 1 "$dir/err")"
}

case $mode in
determinism)
    "$emm" mesh gen --faces 20000 --seed 1 -o "$dir/a.off" >/dev/null || fail "gen a"
    "$emm" mesh gen --faces 20000 --seed 1 -o "$dir/b.off" >/dev/null || fail "gen b"
    "$emm" mesh gen --faces 20000 --seed 2 -o "$dir/c.off" >/dev/null || fail "gen c"
    "$emm" mesh gen -o "$dir/d.off" >/dev/null || fail "gen d (defaults)"
    cmp -s "$dir/a.off" "$dir/b.off" || fail "same seed, different files"
    cmp -s "$dir/a.off" "$dir/c.off" && fail "different seeds, same file"
    cmp -s "$dir/a.off" "$dir/d.off" || fail "defaults are not --faces 20000 --seed 1"
    for density in clustered uniform; do
        "$emm" mesh gen --faces 3001 --seed 9 --density $density -o "$dir/e1.off" >/dev/null
        "$emm" mesh gen --faces 3001 --seed 9 --density $density -o "$dir/e2.off" >/dev/null
        cmp -s "$dir/e1.off" "$dir/e2.off" || fail "$density: same seed, different files"
    done
    cmp -s "$dir/e1.off" "$dir/a.off" && fail "uniform equals clustered"
    ;;
faces)
    for density in clustered uniform; do
        for n in 100 2000 2001 20000; do
            f="$dir/m-$density-$n.off"
            line=$("$emm" mesh gen --faces $n --seed 3 --density $density -o "$f") || fail "gen $n $density"
            echo "$line"
            faces=$(field "$f" faces)
            verts=$(field "$f" vertices)
            boundary=$(field "$f" "boundary edges")
            # within 1% of n
            [ $((faces * 100)) -ge $((n * 99)) ] && [ $((faces * 100)) -le $((n * 101)) ] ||
                fail "$density $n: $faces faces"
            # the hull: about sqrt(2 n) points, at least 4, of n's parity
            hull=$(awk -v n=$n 'BEGIN { h = int(sqrt(2 * n) + 0.5); if (h < 4) h = 4; if ((h + n) % 2) h++; print h }')
            [ "$boundary" = "$hull" ] || fail "$density $n: $boundary boundary edges, not $hull"
            # Euler for a disc: V - E + F = 1, E = (3F + B) / 2
            [ $((verts - (3 * faces + boundary) / 2 + faces)) -eq 1 ] || fail "$density $n: Euler"
            echo "$line" | grep -q "^wrote $f: $verts vertices, $faces faces\$" || fail "summary '$line'"
        done
    done
    # The acceptance check, and the thesis' structs.
    "$emm" mesh gen --faces 20000 --seed 1 -o "$dir/m.off" >/dev/null || fail "gen 20000"
    "$emm" mesh info "$dir/m.off" | tee "$dir/info"
    faces=$(field "$dir/m.off" faces)
    verts=$(field "$dir/m.off" vertices)
    [ "$faces" -ge 19800 ] && [ "$faces" -le 20200 ] || fail "acceptance: $faces faces"
    [ "$(field "$dir/m.off" "thesis bytes" | sed 's/ .*//; s/,//g')" = $((verts * 80 + faces * 28)) ] ||
        fail "thesis bytes"
    [ "$(grep -c 'thesis' "$dir/info")" = 1 ] || fail "the thesis' bytes are printed more than once"
    grep -q '^bbox: \[0, 0, 0\] - \[1, 1, 0\]$' "$dir/info" || fail "bbox"
    grep -q '^polygons split: 0$' "$dir/info" || fail "polygons split"
    grep -q '^mean edge length: 0\.0' "$dir/info" || fail "mean edge length"
    grep -q '^thesis bytes: 1,3[0-9][0-9],[0-9][0-9][0-9] (Vertex 80 B, Triangle 28 B; 1\.[34][0-9] MB)$' \
        "$dir/info" || fail "thesis bytes line"
    # The hull: about sqrt(2 * 20000) boundary edges, not a square's 4.
    [ "$(field "$dir/m.off" "boundary edges")" = 200 ] || fail "boundary edges"
    # OBJ when the name says so, the same mesh; an unknown extension is refused.
    "$emm" mesh gen --faces 500 --seed 2 -o "$dir/m.obj" >/dev/null || fail "gen .obj"
    "$emm" mesh gen --faces 500 --seed 2 -o "$dir/m2.off" >/dev/null || fail "gen .off"
    head -n 1 "$dir/m.obj" | grep -q '^# emm mesh' && grep -q '^v ' "$dir/m.obj" &&
        grep -q '^f [1-9]' "$dir/m.obj" || fail "the .obj file is not OBJ"
    "$emm" mesh info "$dir/m.obj" | sed 1d >"$dir/obj.info"
    "$emm" mesh info "$dir/m2.off" | sed 1d >"$dir/off.info"
    cmp -s "$dir/obj.info" "$dir/off.info" || fail "OBJ and OFF describe different meshes"
    "$emm" mesh gen --faces 500 -o "$dir/m.stl" >/dev/null 2>"$dir/err"; rc=$?
    [ $rc = 2 ] && grep -q 'must end in .off (OFF) or .obj (OBJ)' "$dir/err" || fail "-o m.stl: $rc"
    [ ! -e "$dir/m.stl" ] || fail "-o m.stl wrote a file"
    "$emm" mesh info --json "$dir/m.off" >"$dir/json" || fail "info --json"
    cat "$dir/json"
    grep -q "\"faces\": $faces," "$dir/json" || fail "json faces"
    grep -q "\"thesis_bytes\": $((verts * 80 + faces * 28))}" "$dir/json" || fail "json thesis bytes"
    ;;
errors)
    expect_status 2 "$emm" mesh gen --faces abc -o "$dir/x.off"
    expect_status 2 "$emm" mesh gen --faces 0 -o "$dir/x.off"
    expect_status 2 "$emm" mesh gen --faces 3 -o "$dir/x.off"
    expect_status 2 "$emm" mesh gen --faces -5 -o "$dir/x.off"
    expect_status 2 "$emm" mesh gen --faces 1000000000000 -o "$dir/x.off"
    expect_status 2 "$emm" mesh gen --faces
    expect_status 2 "$emm" mesh gen --seed x1 -o "$dir/x.off"
    expect_status 2 "$emm" mesh gen --density sparse -o "$dir/x.off"
    expect_status 2 "$emm" mesh gen --faces 100
    expect_status 2 "$emm" mesh gen --bogus -o "$dir/x.off"
    expect_status 2 "$emm" mesh gen stray -o "$dir/x.off"
    [ -e "$dir/x.off" ] && fail "a refused command wrote a file"
    expect_status 1 "$emm" mesh gen --faces 100 -o "$dir/no/such/dir/x.off"
    ls "$dir" | grep -v '^out$' | grep -v '^err$' | grep -q . && fail "left files behind: $(ls "$dir")"
    expect_status 1 "$emm" mesh info "$dir/missing.off"
    printf 'OFF\n3 1 0\n0 0 0\n1 0 0\n' >"$dir/short.off"
    expect_status 1 "$emm" mesh info "$dir/short.off"
    expect_status 2 "$emm" mesh info
    expect_status 2 "$emm" mesh info --bogus "$dir/short.off"
    expect_status 2 "$emm" mesh info "$dir/short.off" "$dir/short.off"
    expect_status 2 "$emm" mesh
    expect_status 2 "$emm" mesh frobnicate
    ;;
help)
    for args in "--help" "mesh --help" "mesh -h" "mesh gen --help" "mesh info --help"; do
        # shellcheck disable=SC2086
        "$emm" $args >"$dir/out" 2>"$dir/err" || fail "emm $args exited $?"
        [ -s "$dir/err" ] && fail "emm $args wrote on stderr"
        grep -q '^usage: emm' "$dir/out" || fail "emm $args: no usage line"
    done
    "$emm" --help | grep -q '^  mesh ' || fail "emm --help does not list mesh"
    "$emm" mesh --help >"$dir/out"
    for word in "mesh gen" "mesh info" "--faces" "--seed" "--density" "--json"; do
        grep -q -- "$word" "$dir/out" || fail "emm mesh --help does not mention $word"
    done
    "$emm" mesh gen --help >"$dir/out"
    for word in "--faces" "--seed" "--density" "clustered" "uniform" "-o, --output"; do
        grep -q -- "$word" "$dir/out" || fail "emm mesh gen --help does not mention $word"
    done
    "$emm" mesh info --help | grep -q -- "--json" || fail "emm mesh info --help: --json"
    ;;
*)
    echo "cli.sh: unknown mode $mode" >&2
    exit 2
    ;;
esac

[ $failures -eq 0 ] || { echo "$failures failures" >&2; exit 1; }
echo "all passed"
