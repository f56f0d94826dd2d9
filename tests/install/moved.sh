#!/bin/sh
# The fixture of the install tests: installs the build into a temporary
# prefix, then moves the prefix, so every later test uses an install whose
# configured paths are all wrong: it must find its libraries and data from
# where its files are.
# Usage: moved.sh BUILD_DIR WORK_DIR
set -eu
build=$1 work=$2
rm -rf "$work"
mkdir -p "$work"
cmake --install "$build" --prefix "$work/staged" >/dev/null
mv "$work/staged" "$work/moved"
[ ! -e "$work/staged" ] || { echo "the prefix was not moved"; exit 1; }
ls "$work/moved/bin/emm" "$work/moved/share/emm/table.txt" >/dev/null
echo "installed to $work/staged, moved to $work/moved"
