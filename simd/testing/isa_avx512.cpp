// AVX-512 kernels that only the tests and benchmarks call (TriangleKernels and the kernel
// suites; compiled with the flags of simd/isa/isa_avx512.cpp). Explicit instantiations only
// (docs/style.md rule 2); check_weak_symbols.sh verifies that every weak symbol is tagged.
#include "simd/triangle/block_kernels.h"

namespace volley::simd {

// For each triangle test: the 16-wide single-ray block kernels and packets of 16 against
// 16-wide blocks;
// the same on 8 lanes (Avx512Ymm, the leaves of the AVX-512 wide BVH) with packets of 8
// and 16, so that every kernel test runs on it as on the other ISAs.
#define VOLLEY_FORMS(test) \
  template struct RayBlockKernels<Avx512, TriangleTest::test>; \
  template struct PacketKernels<Avx512, TriangleTest::test, 16>; \
  template struct RayBlockKernels<Avx512Ymm, TriangleTest::test>; \
  template struct PacketKernels<Avx512Ymm, TriangleTest::test, 8>; \
  template struct PacketKernels<Avx512Ymm, TriangleTest::test, 16>;
VOLLEY_FORMS(moller)
VOLLEY_FORMS(plane)
VOLLEY_FORMS(watertight)
#undef VOLLEY_FORMS

}  // namespace volley::simd
