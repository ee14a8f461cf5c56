// Batch-shading lanes for AVX-512 (16 lanes): explicit instantiation only (docs/style.md rule 2).
// GCC 12 warns that _mm512_sqrt_ps's own undefined pass-through operand "may be used
// uninitialized" (a false positive inside avx512fintrin.h).
#if !defined(__clang__)  // (clang has no such warning)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include "render/shade_lanes.h"

namespace volley::render {

template struct ShadeLanes<xsimd::avx512bw>;

}  // namespace volley::render
