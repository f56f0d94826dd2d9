#!/bin/sh
# The build tree's emm found through PATH (argv[0] a bare "emm") from
# another directory: it finds its shipped table from its own location, as
# `emm table list` and `emm profile` need.
# Usage: path_lookup.sh BIN_DIR
set -eu
bin=$1
cd /
out=$(PATH="$bin:$PATH" emm table list) || { echo "FAIL: emm table list through PATH"; exit 1; }
echo "$out" | sed -n 2p
echo "$out" | grep -q "/data/table.txt:[0-9]" || { echo "FAIL: not the source tree's table"; exit 1; }
echo "path lookup test passed"
