// A single ray with its per-ray precomputation hoisted out of the triangle loop (the
// Woop shear for the watertight test). Plain data, no xsimd.
#pragma once
#include <cstdint>

#include "volley/ray.h"

namespace volley::simd {

/// One ray plus what the kernels would otherwise recompute per leaf. Built by the
/// single-ray walk's entry (simd/wide/single_walk.h) or, for tests, prepare_ray()
/// (simd/testing/prepare_ray.h); immutable afterwards, so one PreparedRay may be reused for every leaf
/// the ray visits. 64 bytes, one cache line.
struct alignas(64) PreparedRay {
  Ray ray;            // 32 bytes: the ray as given
  std::int32_t k[3];  // 12 bytes: watertight axes kx, ky, kz (kz = largest |dir|)
  float s[3];         // 12 bytes: watertight shear Sx, Sy, Sz
  float sure[2];      //  8 bytes: watertight any hit, core::sure_quotient_range(tmin, tmax)
};
static_assert(sizeof(PreparedRay) == 64, "PreparedRay: one cache line");

}  // namespace volley::simd
