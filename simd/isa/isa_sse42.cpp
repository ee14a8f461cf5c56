// SSE4.2 kernels of the library (this file alone, with wide_isa_sse42.cpp, is compiled with
// -msse4.2): the packet kernels the wide BVH's packet walks call at their leaves (the
// single-ray leaf kernels are inlined into the walk). Explicit instantiations only
// (docs/style.md rule 2); check_weak_symbols.sh verifies that every weak symbol is tagged.
// The forms only tests use are in simd/testing/isa_sse42.cpp.
#include "simd/triangle/block_kernels.h"
#include "simd/rays/packet_convert.h"

namespace volley::simd {

// The packet kernels of the one table (kernel_table.h), every triangle test.
VOLLEY_LIBRARY_sse42(VOLLEY_DEFINE_PACKETS)

// volley::load and volley::store of whole packets (src/accel/packet_convert.cpp dispatches).
template struct PacketConvert<Sse42>;

}  // namespace volley::simd
