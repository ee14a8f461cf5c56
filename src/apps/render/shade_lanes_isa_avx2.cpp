// Batch-shading lanes for AVX2 (8 lanes; no FMA is emitted: -ffp-contract=off): explicit instantiation only (docs/style.md rule
// 2).
#include "render/shade_lanes.h"

namespace volley::render {

template struct ShadeLanes<xsimd::fma3<xsimd::avx2>>;

}  // namespace volley::render
