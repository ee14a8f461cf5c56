// prepare_ray: a PreparedRay made by the scalar oracle's own code, for the kernel tests and
// benchmarks (the library's walks prepare their rays themselves: simd/wide/single_walk.h).
#pragma once
#include "simd/rays/prepared_ray.h"
#include "volley/ray.h"

namespace volley::simd {

/// Copies the ray and computes its Woop–Benthin–Wald shear exactly as the scalar oracle's
/// make_woop_ray does (so the kernels agree with it bit for bit). With
/// `with_shear == false` only the ray is copied (moller and plane need nothing else).
PreparedRay prepare_ray(const Ray& ray, bool with_shear = true);

}  // namespace volley::simd
