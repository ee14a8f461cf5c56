#!/bin/sh
# Checks that a shared library exports volley's API and nothing else.
#
# Usage: check_exports.sh LIBVOLLEY.so
# Exit 0 when clean; 1 when a symbol outside the API is exported or a C API function of
# src/volley/volley.h is missing; 2 on a usage error.
#
# The API (the same rules as cmake/volley.map), on demangled dynamic symbols:
#   volley_*                                    the C API (volley.h)
#   volley::Accel members but Accel::Impl's     the C++ API (accel.h); templates carry
#                                               their return type in the demangled name
#   volley::to_string / parse_isa / parse_triangle_test   (options.h)
#   volley::load of RayPacket<16>, <8>, <4>, volley::store of HitPacket<16>
#                                               (packet.h: the whole-packet transposes)
#   typeinfo, typeinfo name and vtable of volley::Error and volley::OutOfMemory (accel.h: catch across the boundary)
set -eu

[ $# -eq 1 ] || { echo "usage: $0 LIBVOLLEY.so" >&2; exit 2; }
lib=$1
[ -r "$lib" ] || { echo "$lib: not readable" >&2; exit 2; }
header=$(dirname "$0")/../../src/volley/volley.h
[ -r "$header" ] || { echo "$header: not readable" >&2; exit 2; }

symbols=$(nm -D --defined-only -C "$lib" | sed -E 's/^[0-9a-f]* *[A-Za-z] //')
api='^volley_[a-z0-9_]+$'
api="$api|^((void|unsigned int|bool) )?volley::Accel::(Accel\(|~Accel\(|[a-z])"
api="$api|^volley::(to_string|parse_isa|parse_triangle_test)\("
api="$api|^volley::load\(volley::RayPacket<(16|8|4)>&, volley::Ray const\*, int\)$"
api="$api|^volley::store\(volley::HitPacket<16> const&, volley::Hit\*, int\)$"
api="$api|^(typeinfo|typeinfo name|vtable) for volley::(Error|OutOfMemory)$"

status=0
extra=$(printf '%s\n' "$symbols" | grep -Ev "$api" | grep . || true)
if [ -n "$extra" ]; then
  echo "$lib exports symbols outside the API:"
  printf '%s\n' "$extra" | sed 's/^/  /'
  status=1
fi

# Every function volley.h (and the volley_masked.h it includes) declares must be there (a
# missing VOLLEY_API or map entry).
missing=""
for f in $(cat "$header" "$(dirname "$header")/volley_masked.h" "$(dirname "$header")/volley_queries.h" | grep -oE 'VOLLEY_API [^(]*\bvolley_[a-z0-9_]+\(' |
           grep -oE 'volley_[a-z0-9_]+\($' | tr -d '('); do
  printf '%s\n' "$symbols" | grep -qx "$f" || missing="$missing $f"
done
if [ -n "$missing" ]; then
  echo "$lib lacks C API functions of volley.h:$missing"
  status=1
fi
printf '%s\n' "$symbols" | grep -q '^volley::Accel::intersect(' || { echo "$lib lacks the C++ API (volley::Accel)"; status=1; }

if [ $status -eq 0 ]; then
  echo "$lib: $(printf '%s\n' "$symbols" | grep -c .) symbols, all API ($(printf '%s\n' "$symbols" | grep -c '^volley_') C functions)"
fi
exit $status
