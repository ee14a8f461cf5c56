// The xsimd architecture tags volley instantiates its kernels for, and their lane counts.
// Safe to include from baseline code: it names the tags and never instantiates a batch.
#pragma once
#include <cstddef>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <xsimd/xsimd.hpp>

#include "volley/options.h"

namespace volley::simd {

/// SSE4.2 kernels (4 float lanes); built into isa_sse42.cpp only.
using Sse42 = xsimd::sse4_2;
/// AVX2 + FMA kernels (8 float lanes); built into isa_avx2.cpp only. docs/style.md: plain
/// xsimd::avx2 would never emit FMA.
using Avx2 = xsimd::fma3<xsimd::avx2>;
/// AVX-512 F/DQ/BW/VL kernels (16 float lanes); built into isa_avx512.cpp only.
using Avx512 = xsimd::avx512bw;
/// AVX-512 kernels on 8 float lanes (ymm registers; the compiler may use AVX-512VL
/// encodings and 32 registers): one ray against the 8-triangle blocks of an AVX-512 wide
/// BVH, whose leaves are sized for 8 (faster for shadow rays than 16-triangle leaves;
/// perf/reports/traversal.md). xsimd treats it as AVX2 + FMA; a tag of its
/// own keeps its symbols apart from isa_avx2.cpp's (docs/style.md rule 2). Built into
/// isa_avx512.cpp only.
struct Avx512Ymm : xsimd::fma3<xsimd::avx2> {
  static constexpr char const* name() noexcept { return "avx512ymm"; }
};

/// Float lanes of `Arch`. Equal to xsimd::batch<float, Arch>::size (asserted where the
/// kernels are instantiated), but computable in baseline code where batch<float, Avx2>
/// is not a complete type.
template <class Arch>
inline constexpr int kLanes = static_cast<int>(Arch::alignment() / sizeof(float));

/// The widest lane count of any ISA: packets and blocks are padded to multiples of it.
inline constexpr int kMaxLanes = 16;

/// The Isa enumerator of an arch tag (for labels and tests).
template <class Arch>
inline constexpr Isa kIsaOf = std::is_same_v<Arch, Avx512Ymm> ? Isa::avx512
                              : kLanes<Arch> == 4             ? Isa::sse42
                              : kLanes<Arch> == 8             ? Isa::avx2
                                                              : Isa::avx512;

/// The arch of the single-ray leaf kernels of Arch's wide BVH, whose lanes are its block
/// width: Arch itself, except AVX-512, whose leaves hold blocks of 8 (Avx512Ymm) while its
/// packets keep 16 lanes.
template <class Arch>
struct SingleRayArchT {
  using type = Arch;
};
template <>
struct SingleRayArchT<Avx512> {
  using type = Avx512Ymm;
};
template <class Arch>
using SingleRayArch = typename SingleRayArchT<Arch>::type;

/// The one switch from a run-time ISA to a compile-time arch tag: f(Sse42{}), f(Avx2{}) or
/// f(Avx512{}) for a resolved SIMD ISA (every f must return the same type). Throws
/// std::invalid_argument for Isa::scalar and Isa::automatic (resolve the ISA first; the
/// scalar oracle is no arch). Empty tags only: safe in baseline code.
template <class F>
decltype(auto) visit_arch(Isa isa, F&& f) {
  switch (isa) {
    case Isa::sse42:
      return f(Sse42{});
    case Isa::avx2:
      return f(Avx2{});
    case Isa::avx512:
      return f(Avx512{});
    case Isa::scalar:
    case Isa::automatic:
      break;
  }
  throw std::invalid_argument(std::string("visit_arch: ") + std::string(to_string(isa)) +
                              " is not a SIMD ISA (resolve it first; scalar runs the oracle)");
}

}  // namespace volley::simd

// xsimd's registers for the Avx512Ymm tag: those of AVX2 + FMA, declared only where the
// AVX-512 kernels are compiled (elsewhere the tag is only named, never instantiated).
#if XSIMD_WITH_AVX512BW
namespace xsimd::types {
XSIMD_DECLARE_SIMD_REGISTER_ALIAS(volley::simd::Avx512Ymm, fma3<avx2>);
}  // namespace xsimd::types
#endif
