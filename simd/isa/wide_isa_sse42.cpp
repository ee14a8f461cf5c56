// Wide-BVH traversal kernels for SSE4.2 (this file alone, with isa_sse42.cpp, is compiled with
// the SSE4.2 flags). Explicit instantiations only (docs/style.md rule 2): the bodies live in
// wide_traverse.h, and check_weak_symbols.sh verifies that every weak symbol is tagged.
#include "simd/wide/wide_traverse.h"

namespace volley::simd {

template struct WideKernels<Sse42, TriangleTest::moller>;
template struct WideKernels<Sse42, TriangleTest::plane>;
template struct WideKernels<Sse42, TriangleTest::watertight>;
// Options::robust = false: the unpadded slab test (the fast path, and the mutation tests).
template struct WideKernels<Sse42, TriangleTest::moller, false>;
template struct WideKernels<Sse42, TriangleTest::plane, false>;
template struct WideKernels<Sse42, TriangleTest::watertight, false>;

}  // namespace volley::simd
