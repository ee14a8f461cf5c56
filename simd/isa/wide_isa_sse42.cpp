// Wide-BVH traversal kernels for SSE4.2 (this file alone, with isa_sse42.cpp, is compiled with
// the SSE4.2 flags). Explicit instantiations only (docs/style.md rule 2): the bodies live in
// wide_traverse.h, and check_weak_symbols.sh verifies that every weak symbol is tagged.
#include "simd/isa/kernel_table.h"
#include "simd/wide/wide_traverse.h"

namespace volley::simd {

VOLLEY_DEFINE_WIDE(Sse42)  // the one table: simd/isa/kernel_table.h

}  // namespace volley::simd
