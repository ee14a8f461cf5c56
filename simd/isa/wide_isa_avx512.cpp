// Wide-BVH traversal kernels for AVX-512 (this file alone, with isa_avx512.cpp, is compiled with
// the AVX-512 flags). Explicit instantiations only (docs/style.md rule 2): the bodies live in
// wide_traverse.h, and check_weak_symbols.sh verifies that every weak symbol is tagged.
// GCC 12's avx512fintrin.h builds _mm512_max_ps, _mm512_min_ps and _mm512_extractf64x4_pd
// (which _mm512_castps512_ps256 calls) on _mm512_undefined_*(), a self-initialised
// variable that -Wuninitialized and -Wmaybe-uninitialized report once inlined here: a false
// positive of the compiler's own header (GCC bug 105593), silenced for this file only.
#if !defined(__clang__)  // (clang has no such warning)
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include "simd/isa/kernel_table.h"
#include "simd/wide/wide_traverse.h"

namespace volley::simd {

VOLLEY_DEFINE_WIDE(Avx512)  // the one table: simd/isa/kernel_table.h

}  // namespace volley::simd
