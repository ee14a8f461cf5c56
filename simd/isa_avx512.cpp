// AVX-512 kernels (this file alone is compiled with -mavx512f/dq/bw/vl -mavx2 -mfma).
// Explicit instantiations only (STYLE rule 2): the bodies live in block_kernels.h and the
// test headers, and check_weak_symbols.sh verifies that every weak symbol here is tagged.
#include "simd/block_kernels.h"

namespace volley::simd {

template struct RayBlockKernels<Avx512, TriangleTest::moller>;
template struct RayBlockKernels<Avx512, TriangleTest::plane>;
template struct RayBlockKernels<Avx512, TriangleTest::watertight>;
template struct PacketKernels<Avx512, TriangleTest::moller, 16>;
template struct PacketKernels<Avx512, TriangleTest::plane, 16>;
template struct PacketKernels<Avx512, TriangleTest::watertight, 16>;

}  // namespace volley::simd
