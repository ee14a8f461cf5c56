// Wide-BVH traversal kernels for AVX2 + FMA (this file alone, with isa_avx2.cpp, is compiled with
// the AVX2 + FMA flags). Explicit instantiations only (docs/style.md rule 2): the bodies live in
// wide_traverse.h, and check_weak_symbols.sh verifies that every weak symbol is tagged.
#include "simd/isa/kernel_table.h"
#include "simd/wide/wide_traverse.h"

namespace volley::simd {

VOLLEY_DEFINE_WIDE(Avx2)  // the one table: simd/isa/kernel_table.h

// Any-hit double packets (32 rays walked as one; WideAccel::occluded(RayPacket<32>)).
template std::uint32_t WideKernels<Avx2, TriangleTest::moller, true, 32>::occluded(const View&, const RayPacket<32>&);
template std::uint32_t WideKernels<Avx2, TriangleTest::plane, true, 32>::occluded(const View&, const RayPacket<32>&);
template std::uint32_t WideKernels<Avx2, TriangleTest::watertight, true, 32>::occluded(const View&,
                                                                                    const RayPacket<32>&);
template std::uint32_t WideKernels<Avx2, TriangleTest::moller, false, 32>::occluded(const View&, const RayPacket<32>&);
template std::uint32_t WideKernels<Avx2, TriangleTest::plane, false, 32>::occluded(const View&, const RayPacket<32>&);
template std::uint32_t WideKernels<Avx2, TriangleTest::watertight, false, 32>::occluded(const View&,
                                                                                     const RayPacket<32>&);

}  // namespace volley::simd
