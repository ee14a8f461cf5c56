#!/bin/sh
# Checks that per-ISA kernel objects export no function an other object could share.
#
# Usage: check_weak_symbols.sh [--isa sse42|avx2|avx512] OBJ...
# Without --isa the ISA of each object is read from its name (isa_sse42, isa_avx2,
# isa_avx512). Exit 0 when clean, 1 when a symbol is untagged, 2 on a usage error.
#
# Why (docs/style.md rule 2): an inline or template function compiled in isa_avx2.cpp is a weak
# symbol; if a baseline file (or isa_sse42.cpp) emits the same symbol, the linker keeps one
# copy, possibly the AVX2 one, and the baseline caller dies with an illegal instruction on
# an older CPU. Such a clash is impossible only for functions whose name carries an arch
# tag that no other object instantiates.
#
# Criterion: every defined global function symbol (nm types T, W, i) of an object must
# name, in its demangled form, at least one xsimd arch tag of that object's ISA group:
#   sse42:  xsimd::sse2 sse3 ssse3 sse4_1 sse4_2
#   avx2:   xsimd::avx avx2 fma3<xsimd::avx2>
#   avx512: xsimd::avx512f avx512cd avx512dq avx512bw, volley::simd::Avx512Ymm (arch.h: AVX-512
#           on 8 lanes, an AVX2 tag to xsimd but instantiated in the AVX-512 objects only)
# The groups are disjoint, so a tagged symbol of one object can never be emitted by another
# per-ISA object, nor by baseline code (which never instantiates a kernel: extern templates).
# Data symbols (V, u, D, B, R) hold no instructions and are not checked.
set -eu

isa=""
if [ "${1:-}" = "--isa" ]; then
  [ $# -ge 2 ] || { echo "usage: $0 [--isa sse42|avx2|avx512] OBJ..." >&2; exit 2; }
  isa=$2
  shift 2
fi
[ $# -ge 1 ] || { echo "usage: $0 [--isa sse42|avx2|avx512] OBJ..." >&2; exit 2; }

status=0
for obj in "$@"; do
  this=$isa
  if [ -z "$this" ]; then
    case $(basename "$obj") in
      *isa_sse42*) this=sse42 ;;
      *isa_avx512*) this=avx512 ;;
      *isa_avx2*) this=avx2 ;;
      *) echo "$obj: cannot tell its ISA from the name; pass --isa" >&2; exit 2 ;;
    esac
  fi
  case $this in
    sse42) tags='xsimd::(sse2|sse3|ssse3|sse4_1|sse4_2)\b' ;;
    avx2) tags='xsimd::(avx|avx2)\b|xsimd::fma3<xsimd::avx2>' ;;
    avx512) tags='xsimd::avx512(f|cd|dq|bw)\b|volley::simd::Avx512Ymm\b' ;;
    *) echo "unknown ISA '$this'" >&2; exit 2 ;;
  esac
  [ -r "$obj" ] || { echo "$obj: not readable" >&2; exit 2; }
  functions=$(nm -C --defined-only "$obj" | awk '$2 == "T" || $2 == "W" || $2 == "i" { $1 = ""; $2 = ""; sub(/^  /, ""); print }')
  count=$(printf '%s\n' "$functions" | grep -c . || true)
  bad=$(printf '%s\n' "$functions" | grep -Ev "$tags" | grep . || true)
  if [ -n "$bad" ]; then
    echo "$obj ($this): functions without a $this arch tag (could be shared with other objects):"
    printf '%s\n' "$bad" | sed 's/^/  /'
    status=1
  else
    echo "$obj ($this): $count functions, all tagged"
  fi
done
exit $status
