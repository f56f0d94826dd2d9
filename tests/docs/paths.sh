#!/bin/sh
# Every file a document names exists: each `path` in backquotes in the
# given documents that looks like a file of the tree (a folder and a name,
# or a name with a source or document extension) must be found — as
# written from the repository's root, under include/ for a public header
# (`emm/config.h`), or by its name anywhere in the tree for a bare file
# name (`session_decide.c`, listed after its folder). Globs match at least
# one file; NAME in a path is a template (`shim/capture_NAME.c`), not a file.
#   sh paths.sh ROOT DOC...
set -u
root=${1:?usage: paths.sh ROOT DOC...}
shift
cd "$root" || exit 2
status=0
for doc in "$@"; do
  [ -f "$doc" ] || { echo "$doc: no such document"; status=1; continue; }
  # The backquoted words, one a line, with the line they are on.
  grep -n '`' "$doc" | while IFS= read -r line; do
    num=${line%%:*}
    printf '%s\n' "${line#*:}" | grep -o '`[^`]*`' | tr -d '`' | while IFS= read -r tok; do
      case $tok in
        *NAME*|*' '*|-*|*'='*|*'('*|*'$'*|*'<'*|*'%'*) continue ;;
      esac
      case $tok in
        */*|*.c|*.h|*.cpp|*.md|*.sh|*.txt|*.cmake) ;;
        *) continue ;;
      esac
      case $tok in
        build/*|/*|*://*|lib/*|bin/*|share/*|*.so|*.so.*) continue ;; # outputs, not sources
      esac
      found=
      for cand in "$tok" "include/$tok"; do
        # shellcheck disable=SC2086  # a glob is meant to expand
        for f in $cand; do [ -e "$f" ] && found=1 && break; done
        [ -n "$found" ] && break
      done
      if [ -z "$found" ] && [ "${tok#*/}" = "$tok" ]; then
        [ -n "$(find . -path ./build -prune -o -path './build-*' -prune -o -name "$tok" -print | head -1)" ] && found=1
      fi
      [ -n "$found" ] || { echo "$doc:$num: names $tok, which is not in the tree"; echo x >> "${TMPDIR:-/tmp}/emm-paths.$$"; }
    done
  done
done
if [ -e "${TMPDIR:-/tmp}/emm-paths.$$" ]; then
  rm -f "${TMPDIR:-/tmp}/emm-paths.$$"
  status=1
fi
[ $status -eq 0 ] && echo "paths: every file named in $* exists"
exit $status
