// Wide-BVH traversal kernels (simd/wide/kernels.h: WideKernels and the files of its
// parts). Bodies templated on Arch, instantiated only in the per-ISA files
// wide_isa_sse42.cpp, wide_isa_avx2.cpp, wide_isa_avx512.cpp; the extern template
// declarations below keep every other file from instantiating them.
#pragma once
#include "simd/isa/kernel_table.h"
#include "simd/wide/frustum_walk.h"
#include "simd/wide/kernels.h"
#include "simd/wide/packet_entry.h"
#include "simd/wide/packet_queries.h"
#include "simd/wide/packet_walk.h"
#include "simd/wide/point_walk.h"
#include "simd/wide/queries.h"
#include "simd/wide/query_protocol.h"
#include "simd/wide/single_entries.h"
#include "simd/wide/single_walk.h"
#include "simd/wide/stream_queries.h"
#include "simd/wide/stream_walk.h"

namespace volley::simd {

// Explicit instantiation declarations: the definitions live in the per-ISA files only.
VOLLEY_DECLARE_ALL_WIDE()  // the one table: simd/isa/kernel_table.h

}  // namespace volley::simd
