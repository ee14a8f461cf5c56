// SSE4.2 kernels that only the tests and benchmarks call (TriangleKernels and the kernel
// suites; compiled with the flags of simd/isa_sse42.cpp). Explicit instantiations only
// (docs/style.md rule 2); check_weak_symbols.sh verifies that every weak symbol is tagged.
#include "simd/block_kernels.h"

namespace volley::simd {

template struct RayBlockKernels<Sse42, TriangleTest::moller>;
template struct RayBlockKernels<Sse42, TriangleTest::plane>;
template struct RayBlockKernels<Sse42, TriangleTest::watertight>;
template struct PacketKernels<Sse42, TriangleTest::moller, 4>;
template struct PacketKernels<Sse42, TriangleTest::moller, 8>;
template struct PacketKernels<Sse42, TriangleTest::plane, 4>;
template struct PacketKernels<Sse42, TriangleTest::plane, 8>;
template struct PacketKernels<Sse42, TriangleTest::watertight, 4>;
template struct PacketKernels<Sse42, TriangleTest::watertight, 8>;

}  // namespace volley::simd
