// prepare_ray (prepare_ray.h): the per-ray precomputation, done by the scalar oracle's own
// code so the kernels see exactly the constants it would use.
#include "simd/testing/prepare_ray.h"

#include "core/triangle_watertight.h"

namespace volley::simd {

PreparedRay prepare_ray(const Ray& ray, bool with_shear) {
  PreparedRay out{};
  out.ray = ray;
  if (with_shear) {
    const core::WoopRay<float> w = core::make_woop_ray(core::Vec3<float>(ray.dir[0], ray.dir[1], ray.dir[2]));
    out.k[0] = w.kx, out.k[1] = w.ky, out.k[2] = w.kz;
    out.s[0] = w.sx, out.s[1] = w.sy, out.s[2] = w.sz;
    const auto [lo, hi] = core::sure_quotient_range(ray.tmin, ray.tmax);
    out.sure[0] = lo, out.sure[1] = hi;
  }
  return out;
}

}  // namespace volley::simd
