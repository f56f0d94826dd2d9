#!/usr/bin/env bash
# Installs the Debian packages emm needs to build, test and plot, when they
# are missing. As root it runs apt-get; otherwise it prints the exact
# apt-get line to run and fails.
set -euo pipefail

packages=(
  cmake make gcc g++ clang pkg-config   # the build (gcc and clang both supported)
  libc6-dev                             # the C library, libc.a too: tests/shim links a
                                        # program statically (emm run's line for it)
  libclang-rt-14-dev                    # libFuzzer's runtime (tests/fuzz, make fuzz, make check-asan)
  libqhull-dev                          # Delaunay triangulation for the mesh generator
  libunwind-dev                         # call-site names for the shim's tag rules
  libzstd-dev                           # optional zstd compression of trace blocks
  libdw-dev                             # elfutils' DWARF reader: emm annotate's source lines
  gnuplot-nox                           # emm plot
  glmark2-data                          # a real mesh (bunny.obj) for tests and benchmarks
  valgrind                              # --capture valgrind: its tool headers and static core
                                        # libraries build emm's tool; its launcher runs it
  libopenmesh-apps                      # OpenMesh's command-line apps: tests on programs
                                        # nobody here wrote
  libopenmesh-dev                       # OpenMesh's headers: examples/openmesh_regions, a
                                        # traversal of our own over its half-edge mesh
                                        # (the examples only; emm's readers are its own)
  openctm-tools admesh                  # ctmconv (stripped) and admesh: mesh converters and a
                                        # repair tool under emm run (tests/shim/ctmconv.sh,
                                        # tests/sites)
  qhull-bin tetgen                      # qdelaunay and tetgen: a Delaunay triangulator and a
                                        # tetrahedral mesher (tests/sites, tests/thirdparty)
  python3-meshio python3-numpy          # a Python mesh program on meshio and numpy (same)
  python3                               # tests: reports and timelines read back with a strict JSON reader
  time                                  # tests: /usr/bin/time measures the bad-input reproducers
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
    missing+=("$p")
  fi
done
[ ${#missing[@]} -eq 0 ] && exit 0

if [ "$(id -u)" -eq 0 ]; then
  echo "deps: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
else
  echo "deps: missing Debian packages; run:" >&2
  echo "  sudo apt-get install -y ${missing[*]}" >&2
  exit 1
fi
