// Wide-BVH traversal kernels for AVX2 + FMA (this file alone, with isa_avx2.cpp, is compiled with
// the AVX2 + FMA flags). Explicit instantiations only (docs/style.md rule 2): the bodies live in
// wide_traverse.h, and check_weak_symbols.sh verifies that every weak symbol is tagged.
#include "simd/isa/kernel_table.h"
#include "simd/wide/wide_traverse.h"

namespace volley::simd {

VOLLEY_DEFINE_WIDE(Avx2)  // the one table: simd/isa/kernel_table.h

VOLLEY_DEFINE_WIDE_DOUBLE(Avx2)  // any-hit double packets (32 rays walked as one)

}  // namespace volley::simd
