// How the binding's ray queries walk the caller's rays: rows (ox oy oz dx dy dz) converted
// piece by piece into volley's rays just before the kernel needs them, the threads given
// whole pieces, and the answers written piece by piece. The caller's arrays
// (24 bytes a ray in, up to 32 out) are larger than any cache: spreading their traffic over
// the tracing, instead of copying whole arrays before and after it, is what keeps the
// package near the C++ stream API (perf/reports/queries.md).
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>

#include "accel/parallel.h"
#include "volley/accel.h"

namespace volley::python {

inline constexpr float kInf = std::numeric_limits<float>::infinity();

/// Rays per piece of a batch: the unit handed to a thread (at most 1024 rays a task).
inline constexpr std::size_t kPiece = 1024;

/// body(begin, end) over [0, n) in pieces of at most kPiece: on all cores (nthreads = 0),
/// this thread alone (1) or an arena of nthreads (Accel's batch rule). Called without the GIL.
template <class Body>
void parallel(std::size_t n, int nthreads, Body&& body) {
  auto pieces = [&](std::size_t b, std::size_t e) {
    for (std::size_t p = b; p < e; p += kPiece) body(p, std::min(e, p + kPiece));
  };
  accel::for_chunks("nthreads", n, n <= kPiece ? 1 : nthreads, pieces, kPiece);
}

/// Rays [b, b + m) of `rows` as volley's rays over [tnear, tfar), into `out`; the rows a
/// hundred rows on are asked for from memory meanwhile.
void rows_to_rays(const float* rows, std::size_t n, std::size_t b, std::size_t m, float tnear, float tfar, Ray* out);

/// Every hit of each of `n` rays through the geometries its mask selects (intersect_all
/// with one mask per ray): a pass that counts, then one that fills, on nthreads.
HitLists masked_hit_lists(const Accel& accel, const Ray* rays, const std::uint32_t* masks, std::size_t n, int nthreads);

/// body(rays, begin, m) for every piece of up to kPiece rows, converted at once, over
/// nthreads: for the calls that hand the kernel a ray array, whose stream walk sorts the
/// rays of a call among themselves (a group of 16 is too few to sort).
template <class Body>
void for_ray_pieces(const float* rows, std::size_t n, int nthreads, float tnear, float tfar, Body&& body) {
  parallel(n, nthreads, [&](std::size_t b, std::size_t e) {
    alignas(64) Ray rays[kPiece];
    rows_to_rays(rows, n, b, e - b, tnear, tfar, rays);
    body(static_cast<const Ray*>(rays), b, e - b);
  });
}

/// The excluded hits of rays [b, b + m) from rows of (geometry, primitive, instance), into
/// `out` (the exclude= argument of cast_rays and test_occlusions).
void excluded_hits(const std::uint32_t* exclude, std::size_t b, std::size_t m, Hit* out);

/// cast_rays' answer arrays (Open3D's names).
struct HitColumns {
  float* t_hit;
  std::uint32_t* geometry_ids;
  std::uint32_t* primitive_ids;
  float* primitive_uvs;
  float* primitive_normals;
};

/// The hits of the rays [b, b + m) (one piece) into `out` in Open3D's conventions: zeros
/// for the uv and normal of a miss, and for the normal of a degenerate triangle. Plain
/// stores: the piece's lines of the five columns stay in the cache for the next piece's
/// (non-temporal stores of the five streams stalled on Zen 5, perf/reports/queries.md).
void write_hits(const Accel& accel, const Hit* hits, std::size_t b, std::size_t m, const HitColumns& out);

}  // namespace volley::python
