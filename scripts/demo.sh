#!/bin/sh
# make demo: the main job on the embedded default. Generates the thesis'
# default mesh (20,000 clustered faces, seed 1), describes it, then runs the
# three workloads of thesis §4.3 under `emm run`: each prints its own result
# on stdout and emm's summary on stderr (pattern, strategy and why, cycles of
# the strategy and the baselines). The instrumented builds (.sancov) are used
# where clang made them, so every access of the run is simulated; otherwise
# the plain builds run under fault capture, which covers the profiling window.
# Usage: scripts/demo.sh BUILD_DIR
set -eu
build=${1:?usage: scripts/demo.sh BUILD_DIR}
bin=$build/bin
mesh=$build/default-mesh.off
reports=$build/demo
mkdir -p "$reports"

heading() { printf '\n== %s\n' "$1"; }

heading "default mesh: emm mesh gen --faces 20000 --seed 1"
"$bin/emm" mesh gen --faces 20000 --seed 1 -o "$mesh"
"$bin/emm" mesh info "$mesh"

run() {
  name=$1
  shift
  prog=$bin/$1
  shift
  if [ -x "$prog.sancov" ]; then
    "$bin/emm" run --capture sancov --report "$reports/$name.json" -- "$prog.sancov" "$@"
  else
    "$bin/emm" run --capture fault --report "$reports/$name.json" -- "$prog" "$@"
  fi
}

heading "short curves (thesis 4.3.1): emm run -- curve_tracing --short"
run curves-short curve_tracing --short "$mesh"

heading "long curves (thesis 4.3.1): emm run -- curve_tracing --long"
run curves-long curve_tracing --long "$mesh"

heading "region growing (thesis 4.3.2): emm run -- region_growing"
run region region_growing "$mesh"

heading "random access (thesis 4.3.3): emm run -- random_access"
run random random_access "$mesh"

# A program on OpenMesh's half-edge mesh (built when libopenmesh-dev is
# there), tagged by the preset: its points and connectivity.
if [ -x "$bin/openmesh_regions" ]; then
  capture=fault # the window only; emm's Valgrind tool, when built, sees the whole run
  [ -x "$build/lib/emm/valgrind/emm-amd64-linux" ] && capture=valgrind
  heading "OpenMesh: emm run --capture $capture --tag openmesh -- openmesh_regions"
  "$bin/emm" run --capture "$capture" --tag openmesh --report "$reports/openmesh.json" -- \
    "$bin/openmesh_regions" "$mesh"
fi

printf '\nJSON reports: %s/*.json (docs/report.md)\n' "$reports"
