#!/bin/sh
# make demo: the main job on the embedded default. For now: generate the
# thesis' default mesh (20,000 clustered faces, seed 1), describe it, and run
# the three workloads of thesis §4.3 on it natively, printing their results.
# Usage: scripts/demo.sh BUILD_DIR
set -eu
build=${1:?usage: scripts/demo.sh BUILD_DIR}
bin=$build/bin
mesh=$build/default-mesh.off

heading() { printf '\n== %s\n' "$1"; }

heading "default mesh: emm mesh gen --faces 20000 --seed 1"
"$bin/emm" mesh gen --faces 20000 --seed 1 -o "$mesh"
"$bin/emm" mesh info "$mesh"

heading "short curves (thesis 4.3.1): curve_tracing --short"
"$bin/curve_tracing" --short "$mesh"

heading "long curves (thesis 4.3.1): curve_tracing --long"
"$bin/curve_tracing" --long "$mesh"

heading "region growing (thesis 4.3.2): region_growing"
"$bin/region_growing" "$mesh"

heading "random access (thesis 4.3.3): random_access"
"$bin/random_access" "$mesh"
