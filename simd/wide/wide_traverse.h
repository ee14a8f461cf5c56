// Wide-BVH traversal kernels (simd/wide/kernels.h: WideKernels and the files of its
// parts). Bodies templated on Arch, instantiated only in the per-ISA files
// wide_isa_sse42.cpp, wide_isa_avx2.cpp, wide_isa_avx512.cpp; the extern template
// declarations below keep every other file from instantiating them.
#pragma once
#include "simd/wide/frustum_walk.h"
#include "simd/wide/kernels.h"
#include "simd/wide/packet_entry.h"
#include "simd/wide/packet_walk.h"
#include "simd/wide/point_walk.h"
#include "simd/wide/packet_queries.h"
#include "simd/wide/queries.h"
#include "simd/wide/query_protocol.h"
#include "simd/wide/single_entries.h"
#include "simd/wide/single_walk.h"
#include "simd/wide/stream_queries.h"
#include "simd/wide/stream_walk.h"

namespace volley::simd {

// Explicit instantiation declarations: the definitions live in the per-ISA files only.
// Every test twice: Robust = true (default) and false (Options::robust = false).
extern template struct WideKernels<Sse42, TriangleTest::moller>;
extern template struct WideKernels<Sse42, TriangleTest::plane>;
extern template struct WideKernels<Sse42, TriangleTest::watertight>;
extern template struct WideKernels<Sse42, TriangleTest::moller, false>;
extern template struct WideKernels<Sse42, TriangleTest::plane, false>;
extern template struct WideKernels<Sse42, TriangleTest::watertight, false>;
extern template struct WideKernels<Avx2, TriangleTest::moller>;
extern template struct WideKernels<Avx2, TriangleTest::plane>;
extern template struct WideKernels<Avx2, TriangleTest::watertight>;
extern template struct WideKernels<Avx2, TriangleTest::moller, false>;
extern template struct WideKernels<Avx2, TriangleTest::plane, false>;
extern template struct WideKernels<Avx2, TriangleTest::watertight, false>;
// AVX2's any-hit double packets (32 rays walked as one): the entry alone is instantiated.
extern template std::uint32_t WideKernels<Avx2, TriangleTest::moller, true, 32>::occluded(const View&,
                                                                                       const RayPacket<32>&);
extern template std::uint32_t WideKernels<Avx2, TriangleTest::plane, true, 32>::occluded(const View&,
                                                                                      const RayPacket<32>&);
extern template std::uint32_t WideKernels<Avx2, TriangleTest::watertight, true, 32>::occluded(const View&,
                                                                                           const RayPacket<32>&);
extern template std::uint32_t WideKernels<Avx2, TriangleTest::moller, false, 32>::occluded(const View&,
                                                                                        const RayPacket<32>&);
extern template std::uint32_t WideKernels<Avx2, TriangleTest::plane, false, 32>::occluded(const View&,
                                                                                       const RayPacket<32>&);
extern template std::uint32_t WideKernels<Avx2, TriangleTest::watertight, false, 32>::occluded(const View&,
                                                                                            const RayPacket<32>&);
extern template struct WideKernels<Avx512, TriangleTest::moller>;
extern template struct WideKernels<Avx512, TriangleTest::plane>;
extern template struct WideKernels<Avx512, TriangleTest::watertight>;
extern template struct WideKernels<Avx512, TriangleTest::moller, false>;
extern template struct WideKernels<Avx512, TriangleTest::plane, false>;
extern template struct WideKernels<Avx512, TriangleTest::watertight, false>;

}  // namespace volley::simd
