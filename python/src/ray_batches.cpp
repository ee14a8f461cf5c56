#include "ray_batches.h"

#include <cmath>
#include <cstddef>

#include <xmmintrin.h>

namespace volley::python {
namespace {

/// Rays between the rows being converted and the rows asked for from memory.
constexpr std::size_t kPrefetchRays = 128;

}  // namespace

void rows_to_rays(const float* rows, std::size_t n, std::size_t b, std::size_t m, float tnear, float tfar, Ray* out) {
  // One request per row, spread over the conversion (a burst of them would stall it).
  // A row (o0 o1 o2 d0 d1 d2) becomes (o0 o1 o2 tnear | d0 d1 d2 tfar) by two loads inside
  // the row, two unpacks with a bound and two shuffles.
  static_assert(offsetof(Ray, tmin) == 12 && offsetof(Ray, dir) == 16 && offsetof(Ray, tmax) == 28 && sizeof(Ray) == 32,
                "Ray is org, tmin, dir, tmax");
  const __m128 tn = _mm_set1_ps(tnear), tf = _mm_set1_ps(tfar);
  const float* r = rows + 6 * b;
  for (std::size_t i = 0; i < m; ++i, r += 6) {
    if (b + i + kPrefetchRays < n) __builtin_prefetch(r + 6 * kPrefetchRays);
    const __m128 lo = _mm_loadu_ps(r), hi = _mm_loadu_ps(r + 2);               // o0 o1 o2 d0, o2 d0 d1 d2
    const __m128 near = _mm_unpackhi_ps(lo, tn), far = _mm_unpackhi_ps(hi, tf);  // o2 tn d0 tn, d1 tf d2 tf
    _mm_storeu_ps(out[i].org, _mm_shuffle_ps(lo, near, _MM_SHUFFLE(1, 0, 1, 0)));  // o0 o1 o2 tn
    _mm_storeu_ps(out[i].dir, _mm_shuffle_ps(hi, far, _MM_SHUFFLE(1, 2, 2, 1)));   // d0 d1 d2 tf
  }
}

HitLists masked_hit_lists(const Accel& accel, const Ray* rays, const std::uint32_t* masks, std::size_t n, int nthreads) {
  HitLists lists;
  lists.offsets.assign(n + 1, 0);
  parallel(n, nthreads, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) lists.offsets[i + 1] = accel.count_intersections(rays[i], masks[i]);
  });
  for (std::size_t i = 0; i < n; ++i) lists.offsets[i + 1] += lists.offsets[i];
  lists.hits.resize(lists.offsets[n]);
  parallel(n, nthreads, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i)
      accel.intersect_all(rays[i], lists.hits.data() + lists.offsets[i], lists.offsets[i + 1] - lists.offsets[i], masks[i]);
  });
  return lists;
}

void excluded_hits(const std::uint32_t* exclude, std::size_t b, std::size_t m, Hit* out) {
  for (std::size_t i = 0; i < m; ++i) {
    const std::uint32_t* e = exclude + 3 * (b + i);
    out[i] = Hit{kInf, 0.0f, 0.0f, e[1], e[0], e[2]};
  }
}

void write_hits(const Accel& accel, const Hit* hits, std::size_t b, std::size_t m, const HitColumns& out) {
  float* t = out.t_hit + b;
  std::uint32_t* geometry = out.geometry_ids + b;
  std::uint32_t* primitive = out.primitive_ids + b;
  float* uv = out.primitive_uvs + 2 * b;
  float* normals = out.primitive_normals + 3 * b;
  for (std::size_t i = 0; i < m; ++i) {
    const Hit& h = hits[i];
    const bool hit = h.hit();
    t[i] = h.t, geometry[i] = h.geom, primitive[i] = h.prim;
    uv[2 * i] = hit ? h.u : 0.0f, uv[2 * i + 1] = hit ? h.v : 0.0f;
  }
  accel.geometric_normals(hits, m, normals, 1);
  for (std::size_t i = 0; i < 3 * m; ++i) normals[i] = std::isnan(normals[i]) ? 0.0f : normals[i];
}

}  // namespace volley::python
