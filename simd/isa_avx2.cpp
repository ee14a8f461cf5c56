// AVX2 + FMA kernels (this file alone is compiled with -mavx2 -mfma).
// Explicit instantiations only (docs/style.md rule 2): the bodies live in block_kernels.h and the
// test headers, and check_weak_symbols.sh verifies that every weak symbol here is tagged.
#include "simd/block_kernels.h"

namespace volley::simd {

template struct RayBlockKernels<Avx2, TriangleTest::moller>;
template struct RayBlockKernels<Avx2, TriangleTest::plane>;
template struct RayBlockKernels<Avx2, TriangleTest::watertight>;
template struct PacketKernels<Avx2, TriangleTest::moller, 8>;
template struct PacketKernels<Avx2, TriangleTest::moller, 16>;
template struct PacketKernels<Avx2, TriangleTest::plane, 8>;
template struct PacketKernels<Avx2, TriangleTest::plane, 16>;
template struct PacketKernels<Avx2, TriangleTest::watertight, 8>;
template struct PacketKernels<Avx2, TriangleTest::watertight, 16>;

}  // namespace volley::simd
