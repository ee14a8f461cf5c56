// Batch-shading lanes for AVX-512 (16 lanes): explicit instantiation only (STYLE rule 2).
#include "render/shade_lanes.h"

namespace volley::render {

template struct ShadeLanes<xsimd::avx512bw>;

}  // namespace volley::render
