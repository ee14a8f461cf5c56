// The xsimd architecture tags volley instantiates its kernels for, and their lane counts.
// Safe to include from baseline code: it names the tags and never instantiates a batch.
#pragma once
#include <cstddef>

#include <xsimd/xsimd.hpp>

#include "volley/options.h"

namespace volley::simd {

/// SSE4.2 kernels (4 float lanes); built into isa_sse42.cpp only.
using Sse42 = xsimd::sse4_2;
/// AVX2 + FMA kernels (8 float lanes); built into isa_avx2.cpp only. STYLE.md: plain
/// xsimd::avx2 would never emit FMA.
using Avx2 = xsimd::fma3<xsimd::avx2>;
/// AVX-512 F/DQ/BW/VL kernels (16 float lanes); built into isa_avx512.cpp only.
using Avx512 = xsimd::avx512bw;

/// Float lanes of `Arch`. Equal to xsimd::batch<float, Arch>::size (asserted where the
/// kernels are instantiated), but computable in baseline code where batch<float, Avx2>
/// is not a complete type.
template <class Arch>
inline constexpr int kLanes = static_cast<int>(Arch::alignment() / sizeof(float));

/// The widest lane count of any ISA: packets and blocks are padded to multiples of it.
inline constexpr int kMaxLanes = 16;

/// The Isa enumerator of an arch tag (for labels and tests).
template <class Arch>
inline constexpr Isa kIsaOf = kLanes<Arch> == 4 ? Isa::sse42 : kLanes<Arch> == 8 ? Isa::avx2 : Isa::avx512;

}  // namespace volley::simd
