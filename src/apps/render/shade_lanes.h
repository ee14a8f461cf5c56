// The SIMD part of batch shading (shade_batch.h), templated on the xsimd arch so that it
// runs as wide as the CPU allows: surface points, their error bounds and facing normals,
// then per point light the Phong cosines, the shadow-ray origins (pbrt's offset_origin,
// rounded away from the surface) and directions. Inputs and outputs are rows of a
// structure-of-arrays buffer; the baseline code gathers the hits into it and writes the
// results back hit by hit. Every expression mirrors Scene::surface_as, render::hit_point,
// queue_direct_lighting and spawn_shadow_ray operation for operation (no contraction:
// the per-ISA files are compiled with -ffp-contract=off), so the results are bit-identical.
// docs/style.md rule 2: nothing here but code templated on Arch (no GLM); the per-ISA files
// shade_lanes_isa_<isa>.cpp hold the explicit instantiations.
#pragma once
#include <cstddef>
#include <cstdint>
#include <limits>
#include <xsimd/xsimd.hpp>

#include "core/rounding.h"

namespace volley::render {

/// Rows of the surface buffer: inputs (the hit triangle's corners, barycentrics, ray
/// direction), then outputs. Each row is `stride` floats, 64-byte aligned.
// One row group a line:
// clang-format off
enum SurfaceRow : int {
  kP0X, kP0Y, kP0Z, kP1X, kP1Y, kP1Z, kP2X, kP2Y, kP2Z,  // in: corners
  kU, kV,                                                // in: barycentrics of corners 1 and 2
  kDirX, kDirY, kDirZ,                                   // in: ray direction
  kPX, kPY, kPZ,           // hit point
  kErrX, kErrY, kErrZ,     // its absolute error bound per axis
  kNX, kNY, kNZ,           // unit geometric normal facing the ray
  kViewX, kViewY, kViewZ,  // unit ray direction
  kFront,                  // 1 when the ray hit the side the normal points to, else 0
  kOffsetScale,            // |n| . (error bound + 2 roundings of max |p|): offset length along n
  kSurfaceRows
};

/// Rows of one light's buffer (outputs).
enum LightRow : int {
  kNDotL,                        // n . l (no shadow ray unless > 0; NaN counts as lit)
  kRDotV,                        // reflect(-l, n) . -view, for the specular term
  kDist2,                        // squared distance to the light
  kOrgX, kOrgY, kOrgZ,           // shadow-ray origin
  kShadowX, kShadowY, kShadowZ,  // shadow-ray direction: light - origin (the light at t = 1)
  kLightRows
};
// clang-format on

template <class Arch>
struct ShadeLanes {
  /// Fills the output rows of `rows` for lanes [0, count); count is a multiple of the
  /// lane count (padding lanes hold an inert triangle).
  static void surfaces(float* rows, std::size_t stride, std::size_t count);
  /// One light at `position`: fills `out` (kLightRows rows of `stride`) from the surface rows.
  static void light(const float* rows, std::size_t stride, std::size_t count, const float position[3], float* out);
};

namespace shade_lanes_detail {

template <class Arch>
using B = xsimd::batch<float, Arch>;

template <class Arch>
struct V3 {
  B<Arch> x, y, z;
};

template <class Arch>
V3<Arch> add(const V3<Arch>& a, const V3<Arch>& b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
template <class Arch>
V3<Arch> sub(const V3<Arch>& a, const V3<Arch>& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
template <class Arch>
V3<Arch> scale(const B<Arch>& s, const V3<Arch>& a) {
  return {s * a.x, s * a.y, s * a.z};
}
template <class Arch>
V3<Arch> abs3(const V3<Arch>& a) {
  return {xsimd::abs(a.x), xsimd::abs(a.y), xsimd::abs(a.z)};
}
/// (x + y) + z, as glm::dot.
template <class Arch>
B<Arch> dot(const V3<Arch>& a, const V3<Arch>& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
/// v * (1 / sqrt(dot)), as glm::normalize.
template <class Arch>
V3<Arch> normalize(const V3<Arch>& a) {
  const B<Arch> inv = B<Arch>(1.0f) / xsimd::sqrt(dot(a, a));
  return {a.x * inv, a.y * inv, a.z * inv};
}
/// std::max(a, b) = a < b ? b : a.
template <class Arch>
B<Arch> max_of(const B<Arch>& a, const B<Arch>& b) {
  return xsimd::select(a < b, b, a);
}
template <class Arch>
V3<Arch> load3(const float* rows, std::size_t stride, int row, std::size_t i) {
  return {B<Arch>::load_aligned(rows + row * stride + i), B<Arch>::load_aligned(rows + (row + 1) * stride + i),
          B<Arch>::load_aligned(rows + (row + 2) * stride + i)};
}
template <class Arch>
void store3(const V3<Arch>& a, float* rows, std::size_t stride, int row, std::size_t i) {
  a.x.store_aligned(rows + row * stride + i);
  a.y.store_aligned(rows + (row + 1) * stride + i);
  a.z.store_aligned(rows + (row + 2) * stride + i);
}

/// std::nextafter(x, +inf) (Up) or (x, -inf) for finite x, on the bit patterns
/// (render::next_float).
template <bool Up, class Arch>
B<Arch> next_float(const B<Arch>& x) {
  using I = xsimd::batch<std::int32_t, Arch>;
  const I bits = xsimd::bitwise_cast<I>(x);
  const B<Arch> zero(0.0f);
  const I step = Up ? xsimd::select(xsimd::bool_cast(x < zero), I(-1), I(1))
                    : xsimd::select(xsimd::bool_cast(x > zero), I(-1), I(1));
  const B<Arch> moved = xsimd::bitwise_cast<B<Arch>>(bits + step);
  // From +-0 the next float is the smallest subnormal of the direction's sign.
  const B<Arch> tiny(Up ? std::numeric_limits<float>::denorm_min() : -std::numeric_limits<float>::denorm_min());
  return xsimd::select(x == zero, tiny, moved);
}

/// Rounds p + offset away from p (offset_origin's last step).
template <class Arch>
B<Arch> round_away(const B<Arch>& moved, const B<Arch>& offset) {
  const B<Arch> zero(0.0f);
  return xsimd::select(offset > zero, next_float<true, Arch>(moved),
                       xsimd::select(offset < zero, next_float<false, Arch>(moved), moved));
}

}  // namespace shade_lanes_detail

template <class Arch>
void ShadeLanes<Arch>::surfaces(float* rows, std::size_t stride, std::size_t count) {
  using namespace shade_lanes_detail;
  using F = B<Arch>;
  constexpr float kGamma2 = core::rounding_gamma(2), kGamma7 = core::rounding_gamma(7);
  constexpr float kGamma8 = core::rounding_gamma(8);
  for (std::size_t i = 0; i < count; i += F::size) {
    // render::hit_point.
    const V3<Arch> a = load3<Arch>(rows, stride, kP0X, i), b = load3<Arch>(rows, stride, kP1X, i),
                   c = load3<Arch>(rows, stride, kP2X, i);
    const F u = F::load_aligned(rows + kU * stride + i), v = F::load_aligned(rows + kV * stride + i);
    const F b0 = F(1.0f) - u - v;
    const V3<Arch> p = add(add(scale(b0, a), scale(u, b)), scale(v, c));
    const V3<Arch> sum_abs = add(add(abs3(scale(b0, a)), abs3(scale(u, b))), abs3(scale(v, c)));
    const V3<Arch> reach_a = abs3(sub(a, p)), reach_b = abs3(sub(b, p)), reach_c = abs3(sub(c, p));
    const V3<Arch> reach{max_of(reach_a.x, max_of(reach_b.x, reach_c.x)),
                         max_of(reach_a.y, max_of(reach_b.y, reach_c.y)),
                         max_of(reach_a.z, max_of(reach_b.z, reach_c.z))};
    const F reach_term = F(kGamma8) * max_of(reach.x, max_of(reach.y, reach.z));
    const V3<Arch> err = add(scale(F(kGamma7), sum_abs), V3<Arch>{reach_term, reach_term, reach_term});
    // The geometric normal of Scene::surface_as, facing the incoming ray.
    const V3<Arch> e1 = sub(b, a), e2 = sub(c, a);
    V3<Arch> ng = normalize(V3<Arch>{e1.y * e2.z - e2.y * e1.z, e1.z * e2.x - e2.z * e1.x, e1.x * e2.y - e2.x * e1.y});
    const V3<Arch> dir = load3<Arch>(rows, stride, kDirX, i);
    const auto front = dot(ng, dir) < F(0.0f);
    ng = {xsimd::select(front, ng.x, -ng.x), xsimd::select(front, ng.y, -ng.y), xsimd::select(front, ng.z, -ng.z)};
    store3(p, rows, stride, kPX, i);
    store3(err, rows, stride, kErrX, i);
    store3(ng, rows, stride, kNX, i);
    store3(normalize(dir), rows, stride, kViewX, i);
    xsimd::select(front, F(1.0f), F(0.0f)).store_aligned(rows + kFront * stride + i);
    // offset_origin's offset length, the same for every light.
    const V3<Arch> abs_p = abs3(p);
    const F p_max = F(kGamma2) * max_of(abs_p.x, max_of(abs_p.y, abs_p.z));
    dot(abs3(ng), add(err, V3<Arch>{p_max, p_max, p_max})).store_aligned(rows + kOffsetScale * stride + i);
  }
}

template <class Arch>
void ShadeLanes<Arch>::light(const float* rows, std::size_t stride, std::size_t count, const float position[3],
                             float* out) {
  using namespace shade_lanes_detail;
  using F = B<Arch>;
  const V3<Arch> light{F(position[0]), F(position[1]), F(position[2])};
  for (std::size_t i = 0; i < count; i += F::size) {
    const V3<Arch> p = load3<Arch>(rows, stride, kPX, i), n = load3<Arch>(rows, stride, kNX, i),
                   view = load3<Arch>(rows, stride, kViewX, i);
    // queue_direct_lighting with ns = ng.
    const V3<Arch> to_light = sub(light, p);
    const F dist2 = dot(to_light, to_light);
    const F len = xsimd::sqrt(dist2);
    const V3<Arch> l{to_light.x / len, to_light.y / len, to_light.z / len};
    dot(n, l).store_aligned(out + kNDotL * stride + i);  // = dot(l, ng): products commute
    // reflect(-l, n) = d - 2 dot(d, n) n with d = -l; then its dot with -view.
    const V3<Arch> ml{-l.x, -l.y, -l.z};
    const V3<Arch> r = sub(ml, scale(F(2.0f) * dot(ml, n), n));
    dot(r, V3<Arch>{-view.x, -view.y, -view.z}).store_aligned(out + kRDotV * stride + i);
    dist2.store_aligned(out + kDist2 * stride + i);
    // spawn_shadow_ray(p, p_error, n, light): offset_origin toward light - p.
    const F side = xsimd::select(dot(to_light, n) < F(0.0f), F(-1.0f), F(1.0f));
    const V3<Arch> offset = scale(side * F::load_aligned(rows + kOffsetScale * stride + i), n);
    const V3<Arch> moved = add(p, offset);
    const V3<Arch> o{round_away<Arch>(moved.x, offset.x), round_away<Arch>(moved.y, offset.y),
                     round_away<Arch>(moved.z, offset.z)};
    store3(o, out, stride, kOrgX, i);
    store3(sub(light, o), out, stride, kShadowX, i);
  }
}

extern template struct ShadeLanes<xsimd::sse4_2>;
extern template struct ShadeLanes<xsimd::fma3<xsimd::avx2>>;
extern template struct ShadeLanes<xsimd::avx512bw>;

}  // namespace volley::render
