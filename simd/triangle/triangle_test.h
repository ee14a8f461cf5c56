// What a vectorized triangle test is to the kernel forms (block_kernels.h): the concept
// every test satisfies (moller.h, plane.h, watertight.h), the kind of decision its
// candidates carry, the ray lanes the two tests without per-ray precomputation share, and
// the one-block test that an ISA may specialise.
#pragma once
#include <concepts>
#include <cstdint>

#include "simd/triangle/kernel_common.h"
#include "simd/rays/prepared_packet.h"
#include "simd/rays/prepared_ray.h"
#include "volley/ray.h"

namespace volley::simd::detail {

/// How a test's candidates (T::Cand) decide a hit.
enum class Decision {
  /// Candidates carry t, u, v; the valid lanes are the hits (plane).
  direct,
  /// Candidates carry t det, u det, v det and den = |det| (no division in the test); the
  /// valid lanes are hits by the scaled comparisons, checked again on the quotient t / den
  /// by T::confirm, since the scaled test rounds its products and the quotient once more
  /// (Möller).
  scaled_checked,
  /// Det-scaled candidates that are only a prefilter: the hits are the lanes T::confirm
  /// accepts on the quotient t / den (watertight). The any-hit forms decide most lanes
  /// without the division (T::depth, T::sure_hit, T::prefilter).
  quotient,
};

/// What every test provides: ray lanes from a prepared ray or a packet, triangle lanes
/// from a block or one triangle broadcast, and the test itself against an upper end.
template <class T>
concept TriangleLanes = requires(const PreparedRay& pr, const PreparedPacket<16>& pp, const typename T::Rays& r,
                                 const typename T::Block& block, const typename T::Tris& tri,
                                 const typename T::Cand& c, typename T::B upper) {
  { T::kDecision } -> std::convertible_to<Decision>;
  { T::broadcast(pr) } -> std::same_as<typename T::Rays>;
  { T::template load<16>(pp, 0) } -> std::same_as<typename T::Rays>;
  { T::load_block(block, r) } -> std::same_as<typename T::Tris>;
  { T::broadcast_tri(block, 0, r) } -> std::same_as<typename T::Tris>;
  { T::test(r, tri, upper) } -> std::same_as<typename T::Cand>;
  c.valid;
  c.t;
  c.u;
  c.v;
};

/// A test whose valid candidates are hits; accept(c, upper) re-answers them for a smaller
/// upper end (the closest-hit lane loop).
template <class T>
concept DirectTest = TriangleLanes<T> && T::kDecision == Decision::direct &&
                     requires(const typename T::Cand& c, typename T::B upper) { T::accept(c, upper); };

/// A det-scaled test checked on its quotient (Decision::scaled_checked).
template <class T>
concept ScaledCheckedTest = TriangleLanes<T> && T::kDecision == Decision::scaled_checked &&
                            requires(const typename T::Rays& r, const typename T::Cand& c, typename T::B t) {
                              c.den;
                              T::accept(c, t);
                              T::confirm(r, c, t, t);
                            };

/// A test decided on the quotient (Decision::quotient), with the any-hit steps.
template <class T>
concept QuotientTest = TriangleLanes<T> && T::kDecision == Decision::quotient &&
                       requires(const PreparedRay& pr, const typename T::Rays& r, const typename T::Tris& tri,
                                const typename T::Cand& c, typename T::B t) {
                         c.den;
                         T::confirm(r, c, t, t);
                         T::depth(r, tri);
                         T::prefilter(r, T::depth(r, tri), t);
                         T::sure_hit(T::depth(r, tri), T::sure_range(pr));
                         T::sure_range(t, t);
                       };

/// A triangle test, of one of the three kinds.
template <class T>
concept TriangleTestLanes = DirectTest<T> || ScaledCheckedTest<T> || QuotientTest<T>;

/// Whether candidates are det-scaled (u, v and t divided by den for the answer).
template <class T>
inline constexpr bool kDetScaled = T::kDecision != Decision::direct;

/// Ray lanes of the tests that need nothing precomputed per ray (Möller, plane).
template <class Arch>
struct PlainRays {
  using Rays = RayLanes<Arch>;
  [[gnu::always_inline]] inline static Rays broadcast(const PreparedRay& r) { return broadcast_ray_lanes<Arch>(r.ray); }
  /// Nothing to precompute per lane: copies the rays.
  template <int K>
  static void prepare(const RayPacket<K>& rays, PreparedPacket<K>& out) {
    out.rays = rays;
  }
  template <int K>
  [[gnu::always_inline]] inline static Rays load(const PreparedPacket<K>& p, int offset) {
    return load_ray_lanes<Arch, K>(p.rays, offset);
  }
};

/// One ray against one block in the closest-hit form: the candidates, and their valid
/// lanes as bits. T::test on the block's lanes; an ISA may specialise it
/// (watertight_vl.h: AVX-512VL mask registers for the single-ray walk's leaves).
template <class Arch, class T, bool EarlyExit>
struct BlockTest {
  [[gnu::always_inline]] inline static void run(const typename T::Rays& r, const typename T::Block& block,
                                                typename T::B upper, typename T::Cand& cand, std::uint32_t& bits) {
    cand = T::template test<EarlyExit>(r, T::load_block(block, r), upper);
    bits = bits_from_mask<Arch>(cand.valid);
  }
};

}  // namespace volley::simd::detail
