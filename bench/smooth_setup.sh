# Sourced by the benchmarks of examples/smooth.c (session_overhead.sh,
# valgrind_overhead.sh) after they set B (the build), FACES and NAME (for
# messages): the generated mesh (build/bench/smoothFACES.obj, made once),
# a temporary directory TMP removed at exit, an environment without EMM_*
# settings, the EMM_TAG rules that find smooth.c's arrays (TAG), and now().
mkdir -p "$B/bench" || exit 1
MESH=$B/bench/smooth$FACES.obj
if [ ! -s "$MESH" ]; then
  "$B/bin/emm" mesh gen --faces "$FACES" --seed 5 -o "$MESH.tmp.obj" >/dev/null &&
    mv "$MESH.tmp.obj" "$MESH" || { echo "$NAME: cannot generate $MESH" >&2; exit 1; }
fi
TMP=$(mktemp -d) || exit 1
trap 'rm -rf "$TMP"' EXIT
unset EMM_TAG EMM_REPORT EMM_TRACE EMM_PROFILE_DUMP EMM_PROFILE EMM_CAPTURE EMM_LOG \
  EMM_STRATEGY EMM_COMPARE EMM_FINALISTS LD_PRELOAD
TAG='vertices:site=load_mesh,stride=12,xyz=0:f32;triangles:site=load_mesh,stride=12,vidx=0:u32'
now() { date +%s%N; }
