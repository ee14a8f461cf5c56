// Scalar oracle: watertight ray/triangle intersection (Woop, Benthin & Wald 2013,
// "Watertight Ray/Triangle Intersection", JCGT 2(1)): triangles sharing an edge or a vertex
// leave no crack between them for rays aimed exactly at the shared points.
#pragma once
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <utility>

#include "core/geometry.h"
#include "core/kernel_constants.h"
#include "core/triangle_moller.h"

namespace volley::core {

/// Whether the watertight kernels of `isa` fuse (intersect_watertight's `Fused`): the same
/// rule as moller_fused_for, FMA where the ISA has the instruction (AVX2, AVX-512). Only the
/// shear and the depth sum fuse; the edge functions never do (watertightness needs both of
/// their products rounded), so every variant is watertight, but the variants may differ in
/// t by an ulp and on which of two triangles a ray through their shared edge hits.
constexpr bool watertight_fused_for(volley::Isa isa) { return moller_fused_for(isa); }

/// Per-ray constants of the watertight test: an axis permutation and a shear that map the
/// ray onto the unit +z axis from the origin. 24 bytes for float.
template <class T>
struct WoopRay {
  int kx;  ///< source axis of the sheared x; 4 bytes
  int ky;  ///< source axis of the sheared y; 4 bytes
  int kz;  ///< axis where |dir| is largest; 4 bytes
  T sx;    ///< dir[kx] / dir[kz]; 4 bytes (float)
  T sy;    ///< dir[ky] / dir[kz]; 4 bytes
  T sz;    ///< 1 / dir[kz]; 4 bytes
};
static_assert(sizeof(WoopRay<float>) == 24);

/// Computes the shear constants of a ray direction (paper, section 3), on the axes of
/// kWoopAxes. A zero, infinite or NaN direction gives constants (NaN, Inf, sz = 0) with
/// which every intersect_watertight misses. Pure function.
template <class T>
WoopRay<T> make_woop_ray(const Vec3<T>& dir) {
  const T d[3] = {dir.x, dir.y, dir.z};  // indexed loads (Vec3's operator[] branches on the index)
  const T ax = std::abs(d[0]), ay = std::abs(d[1]), az = std::abs(d[2]);
  const int c = (ax >= ay) | (ax >= az) << 1 | (ay >= az) << 2;
  const int n = (d[0] < 0) | (d[1] < 0) << 1 | (d[2] < 0) << 2;
  const int e = kWoopAxes[static_cast<std::size_t>(c | n << 3)];
  const int kx = e & 3, ky = (e >> 2) & 3, kz = e >> 4;
  return {kx, ky, kz, d[kx] / d[kz], d[ky] / d[kz], T(1) / d[kz]};
}

/// The crossing rule's side of an edge function that is exactly 0: the sign the edge
/// function of the edge P -> Q (sheared 2D coordinates, E = Q.x P.y - Q.y P.x at the origin)
/// takes when the origin moves by an infinitesimal step (1, eta) with 0 < eta << 1: that of
/// Q.y - P.y, or where those are equal, of P.x - Q.x; 0 for P = Q. Antisymmetric (the edge
/// Q -> P gets the opposite sign), a function of the two vertices alone (every triangle
/// sharing the edge sees the same), and the same for both facings (docs/crossings.md).
template <class T>
[[gnu::always_inline]] inline int perturbed_edge_sign(T px, T py, T qx, T qy) {
  if (qy != py) return qy > py ? 1 : -1;
  if (qx != px) return px > qx ? 1 : -1;
  return 0;
}

/// The crossing rule's inside test (Crossing = true in intersect_watertight): exact edge
/// functions du, dv, dw of the sheared vertices a, b, c (float products exact in double),
/// a zero one replaced by perturbed_edge_sign. True iff all three signs are +1 or all -1:
/// the ray moved by the infinitesimal step passes through the triangle's interior, so a
/// closed mesh is crossed once at a shared edge or vertex and a silhouette grazed an even
/// number of times.
/// Always inlined (the per-ISA kernels call it: docs/style.md rule 2).
template <class T>
[[gnu::always_inline]] inline bool crossing_inside(double du, double dv, double dw, T ax, T ay, T bx, T by, T cx, T cy) {
  const int su = du > 0 ? 1 : du < 0 ? -1 : perturbed_edge_sign(bx, by, cx, cy);  // edge b -> c
  const int sv = dv > 0 ? 1 : dv < 0 ? -1 : perturbed_edge_sign(cx, cy, ax, ay);  // edge c -> a
  const int sw = dw > 0 ? 1 : dw < 0 ? -1 : perturbed_edge_sign(ax, ay, bx, by);  // edge a -> b
  return su != 0 && su == sv && sv == sw;
}

/// Intersects `ray` with the triangle (p0, p1, p2), both facings (no culling); `w` must be
/// make_woop_ray(ray.dir).
///
/// Hit iff the triangle is not degenerate (cross product != 0), the 2D edge functions U, V, W
/// of the sheared triangle at the origin do not have mixed signs, det = U + V + W != 0
/// (finite), and tmin <= t < tmax. On a hit writes `hit` = {t, u, v} with u = V/det (weight
/// of p1), v = W/det (weight of p2) and returns true; on a miss returns false and leaves
/// `hit` untouched. NaN or Inf input fails a comparison: no hit, never NaN out.
///
/// Watertight: each vertex is sheared by itself (same rounding in every triangle), and the
/// sign of each edge function is exact for the sheared vertices (float: recomputed in double
/// when one is 0), so triangles sharing an edge see exactly opposite edge functions.
/// Requires exact products (no FMA contraction): the project builds with -ffp-contract=off.
/// `Fused`: the shear a[kx] - sx a[kz] and the depth sum U az + V bz + W cz rounded once per
/// product-and-add (std::fma), as the AVX2 and AVX-512 kernels compute them
/// (watertight_fused_for); each vertex is still sheared by itself, so nothing cracks.
/// `Crossing`: the exactly-once rule of the crossing queries (count, all hits, contains):
/// an edge function that is exactly 0 takes the side of an infinitesimal move of the ray
/// (crossing_inside) instead of going with either sign, so a ray through a shared edge or
/// vertex hits exactly one of the triangles there that it crosses (docs/crossings.md).
/// Pure function, thread safe.
///
/// The prefilter before the division: the scaled hit distance t * det is tested against
/// [tmin, tmax] * |det| with det's sign folded in, so most rejected candidates need no
/// division (paper, section 3.5); false for NaN. It never rejects a t that the quotient test
/// accepts. Upper end: t < tmax in float means t_scaled / det < tmax exactly (rounding is
/// monotonic and tmax a float), so ts < tmax * |det| exactly and ts <= fl(tmax * |det|),
/// subnormal products included. A strict ts < fl(tmax * |det|) rejected triangles 1 ulp
/// nearer than the current hit (rays aimed at shared vertices), and the closest hit depended
/// on the visiting order. Lower end: tmin widened by kScaledPad (2 eps, more than the
/// rounding of the quotient and of the products). The SIMD kernels compute the same bounds.
template <class T, bool Fused = false, bool Crossing = false>
bool intersect_watertight(const RayT<T>& ray, const WoopRay<T>& w, const Vec3<T>& p0, const Vec3<T>& p1,
                          const Vec3<T>& p2, TriHit<T>& hit) {
  // Zero-area triangle: no hit (as pbrt-v4). Its sheared vertices are collinear only up to
  // rounding, and a ray through the segment could see three same-signed residues.
  if (glm::cross(p1 - p0, p2 - p0) == Vec3<T>(0)) return false;

  // An infinite dir[kz] gives sz = 0, which would put every hit at t = 0; NaN fails too.
  if (!(std::abs(w.sz) > 0)) return false;

  // Vertices relative to the ray origin.
  const Vec3<T> a = p0 - ray.org;
  const Vec3<T> b = p1 - ray.org;
  const Vec3<T> c = p2 - ray.org;

  // Shear so the ray runs along +z; the z scaling is deferred to the depth test.
  using moller_detail::mul_add;
  const T ax = mul_add<Fused>(-w.sx, a[w.kz], a[w.kx]);
  const T ay = mul_add<Fused>(-w.sy, a[w.kz], a[w.ky]);
  const T bx = mul_add<Fused>(-w.sx, b[w.kz], b[w.kx]);
  const T by = mul_add<Fused>(-w.sy, b[w.kz], b[w.ky]);
  const T cx = mul_add<Fused>(-w.sx, c[w.kz], c[w.kx]);
  const T cy = mul_add<Fused>(-w.sy, c[w.kz], c[w.ky]);

  // Scaled barycentrics: 2D edge functions at the origin. Plain a*b - c*d on purpose: with
  // -ffp-contract=off both products round, so the triangle across an edge computes exactly
  // the negative; a fused multiply-add rounds only one product and cracks open (leaks:
  // docs/accuracy.md).
  T eu = cx * by - cy * bx;
  T ev = ax * cy - ay * cx;
  T ew = bx * ay - by * ax;

  // A float edge function of exactly 0 may hide a nonzero one: products of floats are exact
  // in double, so recompute there and the sign is exact (paper, section 3.4).
  if constexpr (Crossing) {
    // Exact signs (in double for float input), a zero one decided by the perturbation.
    double du = eu, dv = ev, dw = ew;
    if (std::is_same_v<T, float> && (eu == 0 || ev == 0 || ew == 0)) {
      du = double(cx) * double(by) - double(cy) * double(bx);
      dv = double(ax) * double(cy) - double(ay) * double(cx);
      dw = double(bx) * double(ay) - double(by) * double(ax);
      eu = T(du), ev = T(dv), ew = T(dw);
    }
    if (!crossing_inside(du, dv, dw, ax, ay, bx, by, cx, cy)) return false;
  } else {
    if constexpr (std::is_same_v<T, float>) {
      if (eu == 0 || ev == 0 || ew == 0) {
        eu = float(double(cx) * double(by) - double(cy) * double(bx));
        ev = float(double(ax) * double(cy) - double(ay) * double(cx));
        ew = float(double(bx) * double(ay) - double(by) * double(ax));
      }
    }
    // Mixed signs: the origin is outside. Both facings are accepted (no backface culling).
    if ((eu < 0 || ev < 0 || ew < 0) && (eu > 0 || ev > 0 || ew > 0)) return false;
  }

  // det = 0: the ray lies in the triangle's plane. Written so NaN and Inf fail.
  const T det = eu + ev + ew;
  if (!(std::abs(det) > 0 && std::abs(det) <= std::numeric_limits<T>::max())) return false;

  // Scaled hit distance t * det against [tmin, tmax] * |det| (the prefilter: see above).
  const T az = w.sz * a[w.kz];
  const T bz = w.sz * b[w.kz];
  const T cz = w.sz * c[w.kz];
  const T t_scaled = mul_add<Fused>(ew, cz, mul_add<Fused>(ev, bz, eu * az));
  const T sign = det < 0 ? T(-1) : T(1);
  const T ad = det * sign;
  const T tmin_lo = ray.tmin - std::abs(ray.tmin) * kScaledPad<T>;
  const T lo = tmin_lo * ad, hi = ray.tmax * ad;
  const T ts = t_scaled * sign;
  if (!(ts >= lo && ts <= hi)) return false;

  // Normalize and decide on the quotient: tmin <= t < tmax exactly.
  const T t = t_scaled / det;
  if (!(ray.tmin <= t && t < ray.tmax)) return false;
  hit = {t, ev / det, ew / det};
  return true;
}

/// As above, computing the ray's shear constants on the fly.
template <class T, bool Fused = false, bool Crossing = false>
bool intersect_watertight(const RayT<T>& ray, const Vec3<T>& p0, const Vec3<T>& p1, const Vec3<T>& p2, TriHit<T>& hit) {
  return intersect_watertight<T, Fused, Crossing>(ray, make_woop_ray(ray.dir), p0, p1, p2, hit);
}

}  // namespace volley::core
