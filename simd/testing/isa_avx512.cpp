// AVX-512 kernels that only the tests and benchmarks call (TriangleKernels and the kernel
// suites; compiled with the flags of simd/isa_avx512.cpp). Explicit instantiations only
// (docs/style.md rule 2); check_weak_symbols.sh verifies that every weak symbol is tagged.
#include "simd/block_kernels.h"

namespace volley::simd {

template struct RayBlockKernels<Avx512, TriangleTest::moller>;
template struct RayBlockKernels<Avx512, TriangleTest::plane>;
template struct RayBlockKernels<Avx512, TriangleTest::watertight>;
template struct PacketKernels<Avx512, TriangleTest::moller, 16>;
template struct PacketKernels<Avx512, TriangleTest::plane, 16>;
template struct PacketKernels<Avx512, TriangleTest::watertight, 16>;
// AVX-512 on 8 lanes (Avx512Ymm): the single-ray leaf kernels of the AVX-512 wide BVH
// standalone, and its packet forms, so that every kernel test runs on it as on the other ISAs.
template struct RayBlockKernels<Avx512Ymm, TriangleTest::moller>;
template struct RayBlockKernels<Avx512Ymm, TriangleTest::plane>;
template struct RayBlockKernels<Avx512Ymm, TriangleTest::watertight>;
template struct PacketKernels<Avx512Ymm, TriangleTest::moller, 8>;
template struct PacketKernels<Avx512Ymm, TriangleTest::moller, 16>;
template struct PacketKernels<Avx512Ymm, TriangleTest::plane, 8>;
template struct PacketKernels<Avx512Ymm, TriangleTest::plane, 16>;
template struct PacketKernels<Avx512Ymm, TriangleTest::watertight, 8>;
template struct PacketKernels<Avx512Ymm, TriangleTest::watertight, 16>;

}  // namespace volley::simd
