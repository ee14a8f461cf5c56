// SSE4.2 kernels that only the tests and benchmarks call (TriangleKernels and the kernel
// suites; compiled with the flags of simd/isa/isa_sse42.cpp). Explicit instantiations only
// (docs/style.md rule 2); check_weak_symbols.sh verifies that every weak symbol is tagged.
#include "simd/triangle/block_kernels.h"

namespace volley::simd {

// For each triangle test: the single-ray block kernels, packets of 4 and 8.
#define VOLLEY_FORMS(test) \
  template struct RayBlockKernels<Sse42, TriangleTest::test>; \
  template struct PacketKernels<Sse42, TriangleTest::test, 4>; \
  template struct PacketKernels<Sse42, TriangleTest::test, 8>;
VOLLEY_FORMS(moller)
VOLLEY_FORMS(plane)
VOLLEY_FORMS(watertight)
#undef VOLLEY_FORMS

}  // namespace volley::simd
