#!/bin/sh
# reproduce.sh CASE EMM REGRESS WORK [SANITIZED]: one reproducer of issue 15
# (a file that once crashed, hung or ate memory, or an input such as
# /dev/zero or a directory) through the emm command as a user would run it.
# It must end with exactly one line on stderr that names the input and
# contains the expected words, a non-zero exit status, within 2 s and
# 64 MB of resident memory (measured with /usr/bin/time). A sanitizer build
# (SANITIZED=1) gets 10 s and 512 MB: ASan's shadow memory and checks cost
# that much on any run.
set -u
case_=$1 emm=$2 regress=$3 work=$4 sanitized=${5:-0}
mkdir -p "$work"
rm -f "$work/$case_".*
fail() { echo "FAIL $case_: $*" >&2; exit 1; }

# The regression files start with the harness' selector byte (tests/fuzz):
# the file the command reads is the rest.
strip() { tail -c +2 "$regress/$1" > "$work/$case_.$2"; echo "$work/$case_.$2"; }

stdin=/dev/null
case $case_ in
  mesh_ply_crash)        set -- mesh info "$(strip mesh_binary/ply-crash-36 ply)"; want="not a readable PLY file" ;;
  mesh_ply_no_end)       set -- mesh info "$(strip mesh_binary/ply-hang-no-end-header ply)"; want="end_header" ;;
  mesh_ply_cr)           set -- mesh info "$(strip mesh_binary/ply-hang-cr ply)"; want="not a readable PLY file" ;;
  mesh_off_binary00)     set -- mesh info "$(strip mesh_text/off-binary00 off)"; want="not an OFF file" ;;
  mesh_off_binary0cr)    set -- mesh info "$(strip mesh_text/off-binary0cr off)"; want="not an OFF file" ;;
  mesh_off_binary_2e9)   set -- mesh info "$(strip mesh_text/off-binary-2e9 off)"; want="truncated" ;;
  mesh_obj_f)            set -- mesh info "$(strip mesh_text/obj-f obj)"; want="has 0 corners" ;;
  din_wrap)              set -- trace import --din "$(strip din/wrap-bytes8 din)" --bytes 8 -o "$work/$case_.emmt"
                         want="runs past the end of the 64-bit address space" ;;
  trace_wrap_cache)      set -- replay "$regress/trace/wrap-2-64.emmt" --strategy cache; want="runs past the end" ;;
  trace_wrap_direct)     set -- replay "$regress/trace/wrap-2-64.emmt" --strategy direct; want="runs past the end" ;;
  trace_4gib_cache)      set -- replay "$regress/trace/bytes-4gib.emmt" --strategy cache; want="access of 4294967295 bytes" ;;
  table_dev_zero)        set -- table list --table /dev/zero; want="too large" ;;
  plot_dev_zero)         set -- plot /dev/zero --out "$work/$case_.plots"; want="too large" ;;
  din_dev_zero)          set -- trace import --din /dev/zero -o "$work/$case_.emmt"; want="NUL byte" ;;
  din_stdin_zero)        set -- trace import --din - -o "$work/$case_.emmt"; stdin=/dev/zero; want="stdin:1: NUL byte" ;;
  machine_dev_zero)      set -- machine show --machine /dev/zero; want="too large" ;;
  machine_dir)           set -- machine show --machine "$work"; want="is a directory" ;;
  table_dir)             set -- table list --table "$work"; want="is a directory" ;;
  mesh_dir)              mkdir -p "$work/$case_.off"; set -- mesh info "$work/$case_.off"; want="is a directory" ;;
  trace_dir)             set -- replay "$work" --strategy cache; want="is a directory" ;;
  report_dir)            set -- plot "$work" --out "$work/$case_.plots"; want="is a directory" ;;
  din_dir)               set -- trace import --din "$work" -o "$work/$case_.emmt"; want="is a directory" ;;
  *) fail "unknown case" ;;
esac

limit_s=2 limit_kb=65536
[ "$sanitized" = 1 ] && limit_s=10 limit_kb=524288
/usr/bin/time -o "$work/$case_.time" -f "%e %M" \
  timeout -s KILL $((limit_s * 5)) "$emm" "$@" < "$stdin" > "$work/$case_.out" 2> "$work/$case_.err"
rc=$?
read -r secs kb <<EOT
$(tail -1 "$work/$case_.time")
EOT
[ -n "$kb" ] || fail "no time measured"
echo "$case_: exit $rc, ${secs}s, ${kb} KB: $(cat "$work/$case_.err")"
[ "$rc" -ne 0 ] || fail "exit status 0"
[ "$rc" -lt 128 ] || fail "killed by a signal or the time limit (status $rc)"
[ "$(wc -l < "$work/$case_.err")" = 1 ] || fail "expected one line on stderr"
grep -q "$want" "$work/$case_.err" || fail "the message lacks '$want'"
awk -v s="$secs" -v l="$limit_s" 'BEGIN { exit !(s <= l) }' || fail "took ${secs}s (limit ${limit_s}s)"
[ "$kb" -le "$limit_kb" ] || fail "used ${kb} KB (limit ${limit_kb} KB)"
