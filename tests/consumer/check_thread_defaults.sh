#!/bin/sh
# Checks the one thread rule of the public C++ API (README "Embedding volley", threads):
# every batch call that takes a thread count defaults it to 0, all cores, as the CLI's
# --threads and Python's nthreads do. A default of any other count is reported with its line.
#
# Usage: check_thread_defaults.sh HEADER...
# Exit 0 when every default is 0; 1 when one is not, or when no header declares one.
set -eu

[ $# -ge 1 ] || { echo "usage: $0 HEADER..." >&2; exit 2; }
found=$(grep -Hn 'int threads *=' "$@" || true)
[ -n "$found" ] || { echo "no 'int threads =' default in $*" >&2; exit 1; }
bad=$(printf '%s\n' "$found" | grep -v 'int threads *= *0\b' || true)
if [ -n "$bad" ]; then
  echo "thread-count defaults other than 0 (all cores):" >&2
  printf '%s\n' "$bad" >&2
  exit 1
fi
echo "$(printf '%s\n' "$found" | wc -l) thread-count defaults, all 0"
