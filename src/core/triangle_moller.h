// Scalar oracle: ray/triangle by the notes' algorithm 2, the 3x3 barycentric system
// solved by Cramer's rule (Moller & Trumbore 1997, "Fast, minimum storage ray/triangle
// intersection", JGT 2(1)), in a division-free form.
#pragma once
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/geometry.h"
#include "volley/options.h"

namespace volley::core {

/// Whether the Möller–Trumbore kernels of `isa` fuse their products (intersect_moller's
/// `Fused`): only where the ISA has an FMA instruction, AVX2 and AVX-512. SSE4.2 and the
/// scalar oracle (built for x86-64-v2, where std::fma is a libm call of ~2 ns) compute
/// unfused. The two formulations can differ on hit/miss for ill-conditioned rays
/// (docs/accuracy.md, stress item 13), so whatever compares an ISA with the oracle uses this variant.
/// `automatic` is no formulation: resolve it first (throws std::invalid_argument).
constexpr bool moller_fused_for(volley::Isa isa) {
  switch (isa) {
    case volley::Isa::scalar:
    case volley::Isa::sse42:
      return false;
    case volley::Isa::avx2:
    case volley::Isa::avx512:
      return true;
    case volley::Isa::automatic:
      break;
  }
  throw std::invalid_argument("moller_fused_for: resolve Isa::automatic to an ISA first");
}

/// The default formulation of intersect_moller: the scalar oracle's (Isa::scalar, unfused).
inline constexpr bool kMollerFused = moller_fused_for(volley::Isa::scalar);

namespace moller_detail {

/// a b + c: rounded once when Fused (std::fma), twice otherwise.
template <bool Fused, class T>
T mul_add(T a, T b, T c) {
  if constexpr (Fused)
    return std::fma(a, b, c);
  else
    return a * b + c;
}

/// a b - c d; fused: fma(a, b, -(c d)), the product c d rounded.
template <bool Fused, class T>
T diff_of_products(T a, T b, T c, T d) {
  return mul_add<Fused>(a, b, -(c * d));
}

/// a . b, left to right (as glm::dot when not fused).
template <bool Fused, class T>
T dot3(const Vec3<T>& a, const Vec3<T>& b) {
  return mul_add<Fused>(a.z, b.z, mul_add<Fused>(a.y, b.y, a.x * b.x));
}

}  // namespace moller_detail

/// Intersects `ray` with the triangle (p0, p1, p2), both facings (no culling).
///
/// Solves  [-(p1-p0)  -(p2-p0)  dir] [u v t]^T = p0 - org  by Cramer's rule and reports a
/// hit iff det != 0 (finite), u >= 0, v >= 0, u + v <= 1 and tmin <= t < tmax, decided
/// division-free on the scaled values: with s = sign(det), u det s >= 0, v det s >= 0,
/// (u det + v det) s <= |det|, tmin |det| <= t det s < tmax |det| (each product and sum
/// rounded once). On a hit writes `hit` = {t, u, v} = the scaled values over det, true
/// divisions (hit point = (1-u-v) p0 + u p1 + v p2) and returns true; on a miss returns
/// false and leaves `hit` untouched. The reported t is checked against [tmin, tmax) as
/// well: the scaled range test alone lets it land an ulp outside by the division's rounding.
///
/// The determinants are the triple products of Moller-Trumbore, factored as in Embree's
/// Moller intersector so the normal n = (p1-p0) x (p2-p0) is computed once: a triangle with
/// n == 0 exactly (is_degenerate) gets det == 0 and never hits. With `Fused` the dot and
/// cross products use std::fma as the AVX2/AVX-512 kernels' FMA instructions do; without
/// (the default, kMollerFused) each product and sum rounds, as in the SSE4.2 kernels. n and
/// the edges are never fused (the kernels' blocks store them). The accuracy reference for
/// the SIMD twins: intersect_moller<T, moller_fused_for(isa)> is bit-identical to isa's lanes.
/// NaN or Inf anywhere in the input makes a comparison below fail: no hit, never NaN out.
/// Pure function, thread safe.
template <class T, bool Fused = kMollerFused>
bool intersect_moller(const RayT<T>& ray, const Vec3<T>& p0, const Vec3<T>& p1, const Vec3<T>& p2, TriHit<T>& hit) {
  using namespace moller_detail;
  const Vec3<T> e1 = p1 - p0;
  const Vec3<T> ne2 = -(p2 - p0);
  const Vec3<T> n = glm::cross(e1, p2 - p0);
  const Vec3<T> c = p0 - ray.org;  // right-hand side of the system
  const Vec3<T>& d = ray.dir;

  // det[-e1 -e2 d] = d . (e1 x e2). Written so NaN fails: parallel ray, degenerate
  // triangle (n == 0), overflow (Inf) and NaN input all leave here.
  const T det = dot3<Fused>(d, n);
  const T den = std::abs(det);
  if (!(den > 0 && den <= std::numeric_limits<T>::max())) return false;

  // Cramer: replace one column by c. With r = d x c:
  //   det[c -e2 d] = -e2 . r,   det[-e1 c d] = e1 . r,   det[-e1 -e2 c] = c . n.
  const Vec3<T> r(diff_of_products<Fused>(d.y, c.z, c.y, d.z), diff_of_products<Fused>(d.z, c.x, c.z, d.x),
                  diff_of_products<Fused>(d.x, c.y, c.x, d.y));
  T u = dot3<Fused>(ne2, r), v = dot3<Fused>(e1, r), t = dot3<Fused>(c, n);
  // Fold det's sign in (exact): the tests become those of u, v, t against |det|.
  if (det < 0) u = -u, v = -v, t = -t;
  // Half-plane tests and the half-open range tmin <= t < tmax, as one branch (`&`, not `&&`:
  // an aimed ray's hit/miss is hard to predict); each comparison is false for NaN.
  if (!((u >= 0) & (v >= 0) & (u + v <= den) & (ray.tmin * den <= t) & (t < ray.tmax * den))) return false;
  // The scaled test rounds the products tmin |det| and tmax |det|, the quotient rounds
  // once more: t / |det| can land an ulp outside [tmin, tmax). The reported t decides too.
  const T tq = t / den;
  if (!((ray.tmin <= tq) & (tq < ray.tmax))) return false;

  hit = {tq, u / den, v / den};
  return true;
}

}  // namespace volley::core
