// The nearest point of a triangle to a point: the scalar oracle of the closest-point,
// distance and signed-distance queries, written once for any lane type V (float, double,
// or an xsimd batch in simd/point_block.h) so that the SIMD lanes compute exactly the
// scalar operations in the same order (no FMA: the project builds with -ffp-contract=off).
//
// Method: relative to the first vertex a (w = p - a, edges e1 = b - a, e2 = c - a), the
// point's projection onto the plane with its barycentrics from the 2x2 normal equations;
// inside the triangle the distance is |w.n| / |n| (n = e1 x e2: no cancellation of the
// in-plane part); outside, the nearest of the three edges as clamped segments (ab, ac, bc).
// Branch-free: every candidate is computed and the nearest selected, so a lane's answer
// does not depend on its neighbours. A zero-area triangle has no interior (den = 0) and is
// answered by its edges; NaN vertices (a block's padding) give NaN, which
// never wins a comparison.
#pragma once
#include <cmath>
#include <cstdint>
#include <limits>

namespace volley::core {

/// A point query in flight: the point, the squared search radius that shrinks to the
/// nearest squared distance found, and the answer so far.
struct PointQuery {
  float p[3];
  float d2 = std::numeric_limits<float>::infinity();  ///< bound on entry, the answer's on exit
  float q[3] = {0, 0, 0};                             ///< the nearest point found
  float u = 0, v = 0;                                 ///< its barycentrics (weights of the 2nd and 3rd vertex)
  std::uint32_t prim = 0xffffffffu;                   ///< its triangle (engine id); none while 0xffffffff
};

/// The answer of nearest_on_triangle per lane.
template <class V>
struct PointTriangle {
  V d2;    ///< squared distance
  V u, v;  ///< barycentrics of the nearest point (weights of b and c)
};

/// Scalar lane operations for nearest_on_triangle (float or double).
template <class T>
struct ScalarLaneOps {
  using Mask = bool;
  [[gnu::always_inline]] static T select(bool m, T a, T b) { return m ? a : b; }
  /// x clamped to [0, 1]; NaN -> 0.
  [[gnu::always_inline]] static T clamp01(T x) {
    const T lo = x > T(0) ? x : T(0);
    return lo < T(1) ? lo : T(1);
  }
  [[gnu::always_inline]] static bool and_(bool a, bool b) { return a && b; }
};

/// Nearest point of the triangle (a, a + e1, a + e2) to a + w, per lane: w = p - a, e1 =
/// b - a, e2 = c - a as the caller computed them (the SIMD blocks and the oracle round
/// them alike). Ops: ScalarLaneOps or the SIMD twin.
/// Always inlined: the per-ISA kernels call it, and an out-of-line copy would be a weak
/// symbol shared with baseline code (docs/style.md rule 2).
template <class V, class Ops>
[[gnu::always_inline]] inline PointTriangle<V> nearest_on_triangle(V wx, V wy, V wz, V e1x, V e1y, V e1z, V e2x, V e2y, V e2z) {
  const V d00 = e1x * e1x + e1y * e1y + e1z * e1z;
  const V d01 = e1x * e2x + e1y * e2y + e1z * e2z;
  const V d11 = e2x * e2x + e2y * e2y + e2z * e2z;
  const V d20 = wx * e1x + wy * e1y + wz * e1z;
  const V d21 = wx * e2x + wy * e2y + wz * e2z;
  // Interior: the projection inside by its barycentrics' numerators (den > 0: a proper
  // triangle), so only the answer's u, v are divided (the SIMD lanes, which read d2 alone,
  // drop those divisions); the distance to the plane.
  const V den = d00 * d11 - d01 * d01;
  const V nu = d11 * d20 - d01 * d21, nv = d00 * d21 - d01 * d20;
  const auto inside = Ops::and_(Ops::and_(den > V(0), Ops::and_(nu >= V(0), nv >= V(0))), nu + nv <= den);
  const V bu = nu / den, bv = nv / den;
  const V nx = e1y * e2z - e1z * e2y, ny = e1z * e2x - e1x * e2z, nz = e1x * e2y - e1y * e2x;
  const V wn = wx * nx + wy * ny + wz * nz;
  const V plane_d2 = wn * wn / (nx * nx + ny * ny + nz * nz);
  // Edge ab: a + t e1.
  const V tab = Ops::clamp01(d20 / d00);
  const V abx = wx - tab * e1x, aby = wy - tab * e1y, abz = wz - tab * e1z;
  const V ab_d2 = abx * abx + aby * aby + abz * abz;
  // Edge ac: a + t e2.
  const V tac = Ops::clamp01(d21 / d11);
  const V acx = wx - tac * e2x, acy = wy - tac * e2y, acz = wz - tac * e2z;
  const V ac_d2 = acx * acx + acy * acy + acz * acz;
  // Edge bc: b + t (e2 - e1), from b: w - e1.
  const V fx = e2x - e1x, fy = e2y - e1y, fz = e2z - e1z;
  const V gx = wx - e1x, gy = wy - e1y, gz = wz - e1z;
  const V tbc = Ops::clamp01((gx * fx + gy * fy + gz * fz) / (fx * fx + fy * fy + fz * fz));
  const V bcx = gx - tbc * fx, bcy = gy - tbc * fy, bcz = gz - tbc * fz;
  const V bc_d2 = bcx * bcx + bcy * bcy + bcz * bcz;
  // The nearest edge (ab, then ac, then bc on ties), unless the projection is inside.
  PointTriangle<V> r{ab_d2, tab, V(0)};
  const auto ac_nearer = ac_d2 < r.d2;
  r = {Ops::select(ac_nearer, ac_d2, r.d2), Ops::select(ac_nearer, V(0), r.u), Ops::select(ac_nearer, tac, r.v)};
  const auto bc_nearer = bc_d2 < r.d2;
  r = {Ops::select(bc_nearer, bc_d2, r.d2), Ops::select(bc_nearer, V(1) - tbc, r.u), Ops::select(bc_nearer, tbc, r.v)};
  return {Ops::select(inside, plane_d2, r.d2), Ops::select(inside, bu, r.u), Ops::select(inside, bv, r.v)};
}

/// The scalar oracle for one triangle (float or double) given as a vertex and its two
/// edges (e1 = b - a, e2 = c - a, rounded as the blocks round them): offers it to `query`,
/// kept when strictly nearer than query.d2 (the nearest point a + u e1 + v e2). Returns
/// whether it was kept.
template <class T>
[[gnu::always_inline]] inline bool offer_triangle(PointQuery& query, const T* a, const T* e1, const T* e2, std::uint32_t prim) {
  const T wx = T(query.p[0]) - a[0], wy = T(query.p[1]) - a[1], wz = T(query.p[2]) - a[2];
  const PointTriangle<T> r =
      nearest_on_triangle<T, ScalarLaneOps<T>>(wx, wy, wz, e1[0], e1[1], e1[2], e2[0], e2[1], e2[2]);
  if (!(r.d2 < T(query.d2))) return false;
  query.d2 = float(r.d2);
  for (int k = 0; k < 3; ++k) query.q[k] = float(a[k] + r.u * e1[k] + r.v * e2[k]);
  query.u = float(r.u), query.v = float(r.v), query.prim = prim;
  return true;
}

/// The same from the three vertices (the edges rounded in T).
template <class T>
bool offer_triangle_vertices(PointQuery& query, const T* a, const T* b, const T* c, std::uint32_t prim) {
  const T e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const T e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  return offer_triangle(query, a, e1, e2, prim);
}

}  // namespace volley::core
