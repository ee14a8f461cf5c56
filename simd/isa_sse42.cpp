// SSE4.2 kernels (this file alone is compiled with -msse4.2).
// Explicit instantiations only (docs/style.md rule 2): the bodies live in block_kernels.h and the
// test headers, and check_weak_symbols.sh verifies that every weak symbol here is tagged.
#include "simd/block_kernels.h"

namespace volley::simd {

template struct RayBlockKernels<Sse42, TriangleTest::moller>;
template struct RayBlockKernels<Sse42, TriangleTest::plane>;
template struct RayBlockKernels<Sse42, TriangleTest::watertight>;
template struct PacketKernels<Sse42, TriangleTest::moller, 4>;
template struct PacketKernels<Sse42, TriangleTest::moller, 8>;
template struct PacketKernels<Sse42, TriangleTest::moller, 16>;
template struct PacketKernels<Sse42, TriangleTest::plane, 4>;
template struct PacketKernels<Sse42, TriangleTest::plane, 8>;
template struct PacketKernels<Sse42, TriangleTest::plane, 16>;
template struct PacketKernels<Sse42, TriangleTest::watertight, 4>;
template struct PacketKernels<Sse42, TriangleTest::watertight, 8>;
template struct PacketKernels<Sse42, TriangleTest::watertight, 16>;

}  // namespace volley::simd
