// AVX-512 kernels (this file alone is compiled with -mavx512f/dq/bw/vl -mavx2 -mfma).
// Explicit instantiations only (docs/style.md rule 2): the bodies live in block_kernels.h and the
// test headers, and check_weak_symbols.sh verifies that every weak symbol here is tagged.
#include "simd/block_kernels.h"

namespace volley::simd {

template struct RayBlockKernels<Avx512, TriangleTest::moller>;
template struct RayBlockKernels<Avx512, TriangleTest::plane>;
template struct RayBlockKernels<Avx512, TriangleTest::watertight>;
template struct PacketKernels<Avx512, TriangleTest::moller, 16>;
template struct PacketKernels<Avx512, TriangleTest::plane, 16>;
template struct PacketKernels<Avx512, TriangleTest::watertight, 16>;
// Packets of 16 against the 8-triangle blocks of the AVX-512 wide BVH (arch.h).
template struct PacketKernels<Avx512, TriangleTest::moller, 16, 8>;
template struct PacketKernels<Avx512, TriangleTest::plane, 16, 8>;
template struct PacketKernels<Avx512, TriangleTest::watertight, 16, 8>;

// AVX-512 on 8 lanes (Avx512Ymm): the single-ray leaf kernels of the AVX-512 wide BVH, and
// its packet forms, so that every kernel test runs on it as on the other ISAs.
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
