// SSE4.2 kernels that only the tests and benchmarks call (TriangleKernels and the kernel
// suites; compiled with the flags of simd/isa/isa_sse42.cpp). Explicit instantiations only
// (docs/style.md rule 2); check_weak_symbols.sh verifies that every weak symbol is tagged.
#include "simd/triangle/block_kernels.h"

namespace volley::simd {

// The laboratory's rows of the one table (simd/isa/kernel_table.h), every triangle test.
VOLLEY_TESTING_sse42(VOLLEY_DEFINE_PACKETS, VOLLEY_DEFINE_RAYS)

}  // namespace volley::simd
