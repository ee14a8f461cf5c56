// Fixture for check_weak_symbols.sh (not part of any library): what a per-ISA file must
// not contain. An untagged inline helper, compiled with -mavx2 and not inlined, becomes a
// weak symbol the linker could hand to baseline callers; the check must reject this
// object (the ctest that runs it expects failure).
#include <xsimd/xsimd.hpp>

// GCC: noipa (no inlining, no clones); clang has no noipa, noinline does it there.
#if defined(__clang__)
#define VOLLEY_FIXTURE_OUT_OF_LINE [[gnu::noinline]]
#else
#define VOLLEY_FIXTURE_OUT_OF_LINE [[gnu::noipa]]
#endif

namespace volley::simd::fixture {

/// Untagged: nothing in its name says AVX2.
VOLLEY_FIXTURE_OUT_OF_LINE inline float untagged_sum(const float* p, int n) {
  float s = 0.0f;
  for (int i = 0; i < n; ++i) s += p[i];
  return s;
}

/// Tagged: the arch is a template argument, so the symbol is unique to this ISA.
template <class Arch>
float tagged_sum(const float* p) {
  return xsimd::hadd(xsimd::batch<float, Arch>::load_unaligned(p)) + untagged_sum(p, 3);
}

template float tagged_sum<xsimd::fma3<xsimd::avx2>>(const float*);

}  // namespace volley::simd::fixture
