#!/bin/sh
# 'emm mesh gen --surface' as a user runs it: exact face counts over a range
# of N per surface, each file checked by surface_check.py (closed surfaces
# manifold, consistent orientation, no degenerate triangle, the right Euler
# characteristic), every order; the same options give the same bytes; bad
# options give one clear message.
# usage: surface.sh EMM WORKDIR
set -u
emm=$1
dir=$2
here=$(dirname "$0")
py=/usr/bin/python3
rm -rf "$dir"
mkdir -p "$dir" || exit 1
failures=0

fail() {
    echo "FAIL: $*" >&2
    failures=$((failures + 1))
}

check() { # FILE KIND FACES
    "$py" "$here/surface_check.py" "$1" "$2" "$3" || fail "$1"
}

for kind in sphere torus terrain; do
    ns="20 22 24 26 30 38 50 98 100 1000 4094"
    [ $kind = terrain ] && ns="8 9 10 11 13 21 99 100 101 1001 4095"
    for n in $ns; do
        f="$dir/$kind-$n.off"
        line=$("$emm" mesh gen --surface $kind --faces $n --seed $n -o "$f") || fail "gen $kind $n"
        echo "$line" | grep -q "^wrote $f: [0-9]* vertices, $n faces\$" || fail "summary '$line'"
        check "$f" $kind $n
    done
    for order in random hilbert; do
        "$emm" mesh gen --surface $kind --faces 2000 --order $order -o "$dir/$kind-$order.obj" >/dev/null &&
            "$emm" mesh gen --surface $kind --faces 2000 --order $order -o "$dir/$kind-$order.off" >/dev/null ||
            fail "gen $kind --order $order"
        check "$dir/$kind-$order.off" $kind 2000
        [ "$("$emm" mesh info "$dir/$kind-$order.obj" | sed -n 's/^faces: //p')" = 2000 ] ||
            fail "$kind --order $order: the OBJ file"
    done
    # Determinism: same options, same bytes; another seed, another mesh.
    "$emm" mesh gen --surface $kind --faces 3000 --seed 5 -o "$dir/a.off" >/dev/null
    "$emm" mesh gen --surface $kind --faces 3000 --seed 5 -o "$dir/b.off" >/dev/null
    "$emm" mesh gen --surface $kind --faces 3000 --seed 6 -o "$dir/c.off" >/dev/null
    cmp -s "$dir/a.off" "$dir/b.off" || fail "$kind: same seed, different files"
    cmp -s "$dir/a.off" "$dir/c.off" && fail "$kind: different seeds, same file"
done

# expect_error PATTERN ARGS...: exit status 1 or 2, one message naming the
# problem (and at most the usage hint), nothing on stdout, no file.
expect_error() {
    pattern=$1
    shift
    rm -f "$dir/x.off"
    "$emm" mesh gen "$@" -o "$dir/x.off" >"$dir/out" 2>"$dir/err"
    rc=$?
    [ $rc -eq 1 ] || [ $rc -eq 2 ] || fail "'$*' exited $rc"
    [ "$(wc -l <"$dir/err")" -le 2 ] || fail "'$*': more than two lines on stderr"
    grep -q "$pattern" "$dir/err" || fail "'$*': message is '$(cat "$dir/err")', wanted $pattern"
    [ -s "$dir/out" ] && fail "'$*' wrote on stdout"
    [ -e "$dir/x.off" ] && fail "'$*' wrote a file"
    echo "ok: '$*': $(head -n 1 "$dir/err")"
}
expect_error "a sphere has an even number of faces" --surface sphere --faces 1001
expect_error "a torus has an even number of faces" --surface torus --faces 20001
expect_error "18 faces asked for; a sphere has 20 to" --surface sphere --faces 18
expect_error "density applies to planar meshes only" --surface terrain --density uniform
expect_error "surface" --surface cube

[ $failures -eq 0 ] || exit 1
echo "all surface checks passed"
