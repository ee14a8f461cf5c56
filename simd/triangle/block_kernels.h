// The kernel forms, generic over the triangle test (moller.h, plane.h, watertight.h):
//  - one ray x blocks (single-ray traversal of incoherent rays), closest hit and any hit;
//  - a packet of K rays x one triangle, and x blocks (coherent packets), closest and any.
// Bodies (ray_block_kernels.h, packet_block_kernels.h, on kernel_forms.h) are templated on
// Arch and instantiated only in the per-ISA files (isa_sse42.cpp, isa_avx2.cpp,
// isa_avx512.cpp); the extern template declarations below keep every other file from
// instantiating them.
//
// Closest-hit semantics, all forms: triangles are taken in block order, lane order, and a
// triangle replaces the current hit when it is hit with tmin <= t < upper, where upper
// starts as (hit.t < ray.tmax ? hit.t : ray.tmax) and becomes t of each accepted hit. That
// is the scalar oracle's loop exactly (ties keep the earlier triangle unless the test
// itself says otherwise), so the kernels agree with it triangle by triangle.
#pragma once
#include "simd/triangle/packet_block_kernels.h"
#include "simd/triangle/ray_block_kernels.h"

namespace volley::simd {

// Explicit instantiation declarations: the definitions live in the per-ISA files only
// (one line there per line here): those the wide BVH's walks call in the library's
// (simd/isa_*.cpp), the rest in the testing library's (simd/testing/isa_*.cpp). K = every packet size that is a multiple of the lanes.
extern template struct RayBlockKernels<Sse42, TriangleTest::moller>;
extern template struct RayBlockKernels<Sse42, TriangleTest::plane>;
extern template struct RayBlockKernels<Sse42, TriangleTest::watertight>;
extern template struct PacketKernels<Sse42, TriangleTest::moller, 4>;
extern template struct PacketKernels<Sse42, TriangleTest::moller, 8>;
extern template struct PacketKernels<Sse42, TriangleTest::moller, 16>;
extern template struct PacketKernels<Sse42, TriangleTest::plane, 4>;
extern template struct PacketKernels<Sse42, TriangleTest::plane, 8>;
extern template struct PacketKernels<Sse42, TriangleTest::plane, 16>;
extern template struct PacketKernels<Sse42, TriangleTest::watertight, 4>;
extern template struct PacketKernels<Sse42, TriangleTest::watertight, 8>;
extern template struct PacketKernels<Sse42, TriangleTest::watertight, 16>;

extern template struct RayBlockKernels<Avx2, TriangleTest::moller>;
extern template struct RayBlockKernels<Avx2, TriangleTest::plane>;
extern template struct RayBlockKernels<Avx2, TriangleTest::watertight>;
extern template struct PacketKernels<Avx2, TriangleTest::moller, 8>;
extern template struct PacketKernels<Avx2, TriangleTest::moller, 16>;
extern template struct PacketKernels<Avx2, TriangleTest::plane, 8>;
extern template struct PacketKernels<Avx2, TriangleTest::plane, 16>;
extern template struct PacketKernels<Avx2, TriangleTest::watertight, 8>;
extern template struct PacketKernels<Avx2, TriangleTest::watertight, 16>;

extern template struct RayBlockKernels<Avx512, TriangleTest::moller>;
extern template struct RayBlockKernels<Avx512, TriangleTest::plane>;
extern template struct RayBlockKernels<Avx512, TriangleTest::watertight>;
extern template struct PacketKernels<Avx512, TriangleTest::moller, 16>;
extern template struct PacketKernels<Avx512, TriangleTest::plane, 16>;
extern template struct PacketKernels<Avx512, TriangleTest::watertight, 16>;
extern template struct PacketKernels<Avx512, TriangleTest::moller, 16, 8>;
extern template struct PacketKernels<Avx512, TriangleTest::plane, 16, 8>;
extern template struct PacketKernels<Avx512, TriangleTest::watertight, 16, 8>;

extern template struct RayBlockKernels<Avx512Ymm, TriangleTest::moller>;
extern template struct RayBlockKernels<Avx512Ymm, TriangleTest::plane>;
extern template struct RayBlockKernels<Avx512Ymm, TriangleTest::watertight>;
extern template struct PacketKernels<Avx512Ymm, TriangleTest::moller, 8>;
extern template struct PacketKernels<Avx512Ymm, TriangleTest::moller, 16>;
extern template struct PacketKernels<Avx512Ymm, TriangleTest::plane, 8>;
extern template struct PacketKernels<Avx512Ymm, TriangleTest::plane, 16>;
extern template struct PacketKernels<Avx512Ymm, TriangleTest::watertight, 8>;
extern template struct PacketKernels<Avx512Ymm, TriangleTest::watertight, 16>;

}  // namespace volley::simd
