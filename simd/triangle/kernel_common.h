// Small helpers shared by the triangle kernels. Everything here is templated on Arch
// (docs/style.md rule 2): it is compiled only inside the per-ISA files, and every symbol it can
// emit carries the arch tag.
#pragma once
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>

#include <xsimd/xsimd.hpp>

#include "simd/isa/arch.h"
#include "simd/rays/ray_packet.h"
#include "volley/ray.h"

namespace volley::simd::detail {

/// Float batch of Arch.
template <class Arch>
using FloatB = xsimd::batch<float, Arch>;
/// Lane mask of a float batch.
template <class Arch>
using MaskB = xsimd::batch_bool<float, Arch>;
/// 32-bit integer batch of Arch.
template <class Arch>
using IntB = xsimd::batch<std::int32_t, Arch>;

/// True when Arch keeps lane masks in AVX-512 mask registers (batch_bool is a bit mask).
template <class Arch>
inline constexpr bool kHasMaskRegisters = std::is_base_of_v<xsimd::avx512f, Arch>;

/// Lanes whose bit is set in `bits` (bit i = lane i of this batch).
template <class Arch>
MaskB<Arch> mask_from_bits(std::uint32_t bits) {
  if constexpr (kHasMaskRegisters<Arch>) {
    return MaskB<Arch>(static_cast<typename MaskB<Arch>::register_type>(bits));
  } else {
    alignas(64) std::int32_t lane_bit[kLanes<Arch>];
    for (int i = 0; i < kLanes<Arch>; ++i) lane_bit[i] = std::int32_t(1u << i);
    const IntB<Arch> b = IntB<Arch>::load_aligned(lane_bit) & IntB<Arch>(std::int32_t(bits));
    return xsimd::bool_cast(b != IntB<Arch>(0));
  }
}

/// Bit i set when lane i of `m` is true (the 8.1 stand-in for batch_bool::mask()).
template <class Arch>
std::uint32_t bits_from_mask(MaskB<Arch> m) {
  if constexpr (kHasMaskRegisters<Arch>) {
    return static_cast<std::uint32_t>(static_cast<typename MaskB<Arch>::register_type>(m));
  } else if constexpr (kLanes<Arch> == 8) {
    return static_cast<std::uint32_t>(_mm256_movemask_ps(m));
  } else {
    return static_cast<std::uint32_t>(_mm_movemask_ps(m));
  }
}

/// Lanes of `block` whose triangle id is not `prim`: the excluding queries' filter (a ray
/// that leaves its own triangle skips it by id, not by an offset of its origin).
template <class Arch, class Block>
[[gnu::always_inline]] inline MaskB<Arch> lanes_other_than(const Block& block, std::uint32_t prim) {
  const IntB<Arch> ids = IntB<Arch>::load_aligned(reinterpret_cast<const std::int32_t*>(block.prim));
  return xsimd::bool_cast(ids != IntB<Arch>(static_cast<std::int32_t>(prim)));
}

/// Bit i set when lane i of x has its sign bit set (-0 and negative NaNs included).
template <class Arch>
std::uint32_t sign_bits(FloatB<Arch> x) {
  if constexpr (kHasMaskRegisters<Arch>) {
    return static_cast<std::uint32_t>(_mm512_movepi32_mask(_mm512_castps_si512(x)));
  } else if constexpr (kLanes<Arch> == 8) {
    return static_cast<std::uint32_t>(_mm256_movemask_ps(x));
  } else {
    return static_cast<std::uint32_t>(_mm_movemask_ps(x));
  }
}

/// Lanes where x is finite and nonzero: the oracles' `abs(x) > 0 && abs(x) <= max`, NaN
/// false. One fpclass instruction on AVX-512 (no NaN, zero or infinity class), three
/// operations elsewhere.
template <class Arch>
MaskB<Arch> finite_nonzero(FloatB<Arch> x) {
  if constexpr (kHasMaskRegisters<Arch>) {
    // Classes: 0x01 QNaN, 0x02 +0, 0x04 -0, 0x08 +Inf, 0x10 -Inf, 0x80 SNaN.
    return MaskB<Arch>(static_cast<typename MaskB<Arch>::register_type>(~_mm512_fpclass_ps_mask(x, 0x9f)));
  } else {
    const FloatB<Arch> a = xsimd::abs(x);
    return (a > FloatB<Arch>(0.0f)) & (a <= FloatB<Arch>(std::numeric_limits<float>::max()));
  }
}

/// The comparisons of and_cmp (ordered: false when either side is NaN).
enum class Cmp { ge, gt, le, lt };

/// m & (a op b). One masked compare on AVX-512 (xsimd 8.1 combines masks through general
/// registers there: a mask move each way per &), compare and and elsewhere.
template <Cmp Op, class Arch>
[[gnu::always_inline]] inline MaskB<Arch> and_cmp(MaskB<Arch> m, FloatB<Arch> a, FloatB<Arch> b) {
  if constexpr (kHasMaskRegisters<Arch>) {
    // _CMP_GE_OQ, _CMP_GT_OQ, _CMP_LE_OQ, _CMP_LT_OQ (spelled out: the macros are not
    // defined where the other ISAs' files instantiate nothing of this branch).
    constexpr int kPredicate = Op == Cmp::ge ? 0x1d : Op == Cmp::gt ? 0x1e : Op == Cmp::le ? 0x12 : 0x11;
    return MaskB<Arch>(_mm512_mask_cmp_ps_mask(m, a, b, kPredicate));
  } else if constexpr (Op == Cmp::ge) {
    return m & (a >= b);
  } else if constexpr (Op == Cmp::gt) {
    return m & (a > b);
  } else if constexpr (Op == Cmp::le) {
    return m & (a <= b);
  } else {
    return m & (a < b);
  }
}

/// True when no lane of a, b or c is exactly +-0 (NaN lanes count as nonzero, so the inert
/// NaN padding lanes of a block never look zero).
template <class Arch>
[[gnu::always_inline]] inline bool all_nonzero(FloatB<Arch> a, FloatB<Arch> b, FloatB<Arch> c) {
  if constexpr (kHasMaskRegisters<Arch>) {
    constexpr int kNeqUnordered = 0x04;  // _CMP_NEQ_UQ: true for NaN
    const FloatB<Arch> zero(0.0f);
    typename MaskB<Arch>::register_type k = _mm512_cmp_ps_mask(a, zero, kNeqUnordered);
    k = _mm512_mask_cmp_ps_mask(k, b, zero, kNeqUnordered);
    k = _mm512_mask_cmp_ps_mask(k, c, zero, kNeqUnordered);
    return _kortestc_mask16_u8(k, k) != 0;
  } else {
    const FloatB<Arch> zero(0.0f);
    return xsimd::none((a == zero) | (b == zero) | (c == zero));
  }
}

/// Lanes where a, b and c have the same sign bit: (a ^ b) | (a ^ c) has it clear (one
/// ternary-logic instruction and a compare on AVX-512, an arithmetic shift elsewhere).
template <class Arch>
[[gnu::always_inline]] inline MaskB<Arch> same_sign_bit(FloatB<Arch> a, FloatB<Arch> b, FloatB<Arch> c) {
  using I = IntB<Arch>;
  const I x = xsimd::bitwise_cast<I>((a ^ b) | (a ^ c));
  if constexpr (kHasMaskRegisters<Arch>)
    return MaskB<Arch>(_mm512_cmpgt_epi32_mask(x, I(-1)));
  else
    return ~MaskB<Arch>(static_cast<typename MaskB<Arch>::register_type>(xsimd::bitwise_cast<FloatB<Arch>>(x >> 31)));
}

/// True when Arch has an FMA instruction (AVX2 + FMA3, AVX-512). Only those kernels fuse:
/// elsewhere a fused a b + c would be a libm fmaf call per lane (~2 ns, 15x slower).
template <class Arch>
inline constexpr bool kHasFma = std::is_base_of_v<xsimd::fma3<xsimd::avx2>, Arch> || kHasMaskRegisters<Arch>;

/// The fused forms the kernels use: a b + c, a b - c and c - a b, each rounded once.
enum class Fused { mul_add, mul_sub, neg_mul_add };

/// One fused form, rounded once as std::fma: for the kernels that fuse where their oracle
/// does. One vfmadd/vfmsub/vfnmadd on AVX2 (built with -mfma) and AVX-512. Not xsimd::fma:
/// 8.1 has none for AVX-512 and falls back to an unfused a * b + c there. Not for ISAs
/// without FMA (SSE4.2): their kernels compute unfused, so no silent per-lane emulation can
/// creep in.
template <Fused Form, class Arch>
FloatB<Arch> fused(FloatB<Arch> a, FloatB<Arch> b, FloatB<Arch> c) {
  static_assert(kHasFma<Arch>, "no FMA instruction on this ISA: compute unfused (see kMollerFused)");
  if constexpr (kLanes<Arch> == 16) {
    if constexpr (Form == Fused::mul_add) return _mm512_fmadd_ps(a, b, c);
    if constexpr (Form == Fused::mul_sub) return _mm512_fmsub_ps(a, b, c);
    if constexpr (Form == Fused::neg_mul_add) return _mm512_fnmadd_ps(a, b, c);
  } else {
    if constexpr (Form == Fused::mul_add) return _mm256_fmadd_ps(a, b, c);
    if constexpr (Form == Fused::mul_sub) return _mm256_fmsub_ps(a, b, c);
    if constexpr (Form == Fused::neg_mul_add) return _mm256_fnmadd_ps(a, b, c);
  }
}

/// a b + c rounded once, as std::fma(a, b, c).
template <class Arch>
FloatB<Arch> fused_mul_add(FloatB<Arch> a, FloatB<Arch> b, FloatB<Arch> c) {
  return fused<Fused::mul_add, Arch>(a, b, c);
}
/// a b - c rounded once, as std::fma(a, b, -c).
template <class Arch>
FloatB<Arch> fused_mul_sub(FloatB<Arch> a, FloatB<Arch> b, FloatB<Arch> c) {
  return fused<Fused::mul_sub, Arch>(a, b, c);
}
/// c - a b rounded once, as std::fma(-a, b, c).
template <class Arch>
FloatB<Arch> fused_neg_mul_add(FloatB<Arch> a, FloatB<Arch> b, FloatB<Arch> c) {
  return fused<Fused::neg_mul_add, Arch>(a, b, c);
}

/// Reinterprets 32-bit ids as float lanes (so that select() can carry them with t, u, v).
template <class Arch>
FloatB<Arch> load_ids(const std::uint32_t* ids) {
  return FloatB<Arch>::load_aligned(reinterpret_cast<const float*>(ids));
}

/// A 32-bit id broadcast as float bits.
template <class Arch>
FloatB<Arch> broadcast_id(std::uint32_t id) {
  float f;
  std::memcpy(&f, &id, sizeof f);
  return FloatB<Arch>(f);
}

/// The upper end of the search interval: the nearer of the current hit and the ray's
/// tmax, and NaN when tmax is NaN (so a NaN ray stays hit-free).
template <class Arch>
FloatB<Arch> upper_bound(FloatB<Arch> hit_t, FloatB<Arch> tmax) {
  return xsimd::select(hit_t < tmax, hit_t, tmax);
}

}  // namespace volley::simd::detail

namespace volley::simd::detail {

/// L rays as lanes: one ray broadcast to all lanes, or L consecutive lanes of a packet.
template <class Arch>
struct RayLanes {
  FloatB<Arch> ox, oy, oz;
  FloatB<Arch> dx, dy, dz;
  FloatB<Arch> tmin;
};

/// Lanes offset .. offset + kLanes<Arch> of a packet.
template <class Arch, int K>
RayLanes<Arch> load_ray_lanes(const RayPacket<K>& p, int offset) {
  using B = FloatB<Arch>;
  return {B::load_aligned(p.ox + offset), B::load_aligned(p.oy + offset), B::load_aligned(p.oz + offset),
          B::load_aligned(p.dx + offset), B::load_aligned(p.dy + offset), B::load_aligned(p.dz + offset),
          B::load_aligned(p.tmin + offset)};
}

/// One ray in every lane.
template <class Arch>
RayLanes<Arch> broadcast_ray_lanes(const Ray& r) {
  using B = FloatB<Arch>;
  return {B(r.org[0]), B(r.org[1]), B(r.org[2]), B(r.dir[0]), B(r.dir[1]), B(r.dir[2]), B(r.tmin)};
}

}  // namespace volley::simd::detail
