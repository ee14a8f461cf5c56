// AVX2 + FMA kernels that only the tests and benchmarks call (TriangleKernels and the kernel
// suites; compiled with the flags of simd/isa_avx2.cpp). Explicit instantiations only
// (docs/style.md rule 2); check_weak_symbols.sh verifies that every weak symbol is tagged.
#include "simd/block_kernels.h"

namespace volley::simd {

template struct RayBlockKernels<Avx2, TriangleTest::moller>;
template struct RayBlockKernels<Avx2, TriangleTest::plane>;
template struct RayBlockKernels<Avx2, TriangleTest::watertight>;
template struct PacketKernels<Avx2, TriangleTest::moller, 8>;
template struct PacketKernels<Avx2, TriangleTest::plane, 8>;
template struct PacketKernels<Avx2, TriangleTest::watertight, 8>;

}  // namespace volley::simd
