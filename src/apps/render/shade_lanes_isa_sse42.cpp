// Batch-shading lanes for SSE4.2 (4 lanes, the build's baseline): explicit instantiation only (docs/style.md rule 2).
#include "render/shade_lanes.h"

namespace volley::render {

template struct ShadeLanes<xsimd::sse4_2>;

}  // namespace volley::render
