#!/bin/sh
# What another project does with an installed emm: install into a fresh
# prefix, then build a small program against it twice — through pkg-config
# and through CMake's find_package — and run both, and the installed emm.
# Usage: install_test.sh BUILD_DIR SOURCE_DIR WORK_DIR
set -eu
build=$1 src=$2 work=$3
rm -rf "$work"
mkdir -p "$work"
prefix=$work/prefix
cmake --install "$build" --prefix "$prefix" >/dev/null

libdir=$(dirname "$(find "$prefix" -name 'libemm.so' | head -n 1)")
[ -n "$libdir" ] || { echo "libemm.so was not installed"; exit 1; }

# pkg-config
export PKG_CONFIG_PATH="$libdir/pkgconfig"
cc -o "$work/consumer-pc" "$src/tests/install/consumer/main.c" $(pkg-config --cflags --libs emm)
out=$(LD_LIBRARY_PATH="$libdir" "$work/consumer-pc")
echo "pkg-config: $out"
case $out in *": 200 faces") ;; *) echo "unexpected output"; exit 1 ;; esac

# CMake package
cmake -S "$src/tests/install/consumer" -B "$work/consumer-build" \
  -DCMAKE_PREFIX_PATH="$prefix" >/dev/null
cmake --build "$work/consumer-build" >/dev/null
out2=$(LD_LIBRARY_PATH="$libdir" "$work/consumer-build/consumer")
echo "find_package: $out2"
[ "$out" = "$out2" ] || { echo "the two builds differ"; exit 1; }

# The installed command.
"$prefix/bin/emm" --version
echo "install test passed"
