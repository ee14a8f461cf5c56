// The single-ray walk of the wide BVH: the entry prepares the ray itself (screen,
// reciprocal, the watertight shear), then an explicit stack, children sorted by entry
// distance when the query asks for it, leaves handed to the query (queries.h), whose
// block kernels are inlined into the walk. Its steps: the node test (single_slabs.h), the
// child order (child_order.h) and the pop (stack.h).
#pragma once
#include <immintrin.h>

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "simd/wide/child_order.h"
#include "simd/wide/queries.h"
#include "simd/wide/single_slabs.h"

namespace volley::simd {

template <class Arch, TriangleTest Test, bool Robust, int PK>
template <class Query, class Leaves>
bool WideKernels<Arch, Test, Robust, PK>::trace_single(const WideView<Leaves>& bvh, const Ray& ray, std::uint32_t start,
                                                   Query& query) {
  return trace_ray(bvh, ray, start, query);
}

template <class Arch, TriangleTest Test, bool Robust, int PK>
template <class Query, class Leaves>
bool WideKernels<Arch, Test, Robust, PK>::trace_lane(const WideView<Leaves>& bvh, const PreparedPacket<K>& prep,
                                                 const detail::PacketSetup<K>& setup, int i, std::uint32_t start,
                                                 Query& query) {
  const RayPacket<K>& r = prep.rays;
  PreparedRay pr;
  pr.ray = Ray{{r.ox[i], r.oy[i], r.oz[i]}, r.tmin[i], {r.dx[i], r.dy[i], r.dz[i]}, r.tmax[i]};
  if constexpr (Test != TriangleTest::watertight) {
    pr.k[0] = pr.k[1] = pr.k[2] = 0;
    pr.s[0] = pr.s[1] = pr.s[2] = pr.sure[0] = pr.sure[1] = 0.0f;
  } else {
    for (int a = 0; a < 3; ++a) pr.k[a] = prep.k[a][i], pr.s[a] = prep.s[a][i];
    const auto [lo, hi] = Query::kSureRange ? core::sure_quotient_range(pr.ray.tmin, pr.ray.tmax) : std::pair{0.0f, 0.0f};
    pr.sure[0] = lo, pr.sure[1] = hi;
  }
  // (Lane 3 of the reciprocal is never read by the walk.)
  const __m128 inv = _mm_setr_ps(setup.inv[0][i], setup.inv[1][i], setup.inv[2][i], 0.0f);
  if (r.dx[i] != 0.0f && r.dy[i] != 0.0f && r.dz[i] != 0.0f)
    walk<Query, true>(bvh, pr, inv, start, query);
  else
    walk<Query, false>(bvh, pr, inv, start, query);
  return query.answer();
}

template <class Arch, TriangleTest Test, bool Robust, int PK>
template <class Query, class Leaves>
bool WideKernels<Arch, Test, Robust, PK>::trace_ray(const WideView<Leaves>& bvh, const Ray& ray, std::uint32_t start,
                                                Query& query) {
  if (start == wide_ref::kEmptyRef) return query.answer();
  PreparedRay pr;
  __m128 inv;
  const detail::RayScreen screened = prepare_single<Query::kSureRange>(ray, pr, inv);
  if (screened == detail::RayScreen::no_zero_component)
    walk<Query, true>(bvh, pr, inv, start, query);
  else if (screened == detail::RayScreen::zero_component)
    walk<Query, false>(bvh, pr, inv, start, query);
  return query.answer();
}

template <class Arch, TriangleTest Test, bool Robust, int PK>
template <class Query, bool NoZero, class Leaves>
void WideKernels<Arch, Test, Robust, PK>::walk(const WideView<Leaves>& bvh, const PreparedRay& pr, __m128 inv,
                                           std::uint32_t start, Query& query) {
  static_assert(detail::RayQuery<Query, Leaves>, "the single-ray walk takes a RayQuery (query_protocol.h)");
  static_assert(N == 8, "the single-ray node test reads eight children");
  using Slabs = detail::SingleRaySlabs<Arch, Robust, NoZero>;
  using V8 = typename Slabs::V8;
  // (Not const, nor `hits` below: GCC's scalar replacement skips a const aggregate that its
  // constructor writes.)
  Slabs slabs(pr.ray, inv);
  // The upper end of the search (closest hit, as RayBlockKernels: the nearer of hit.t and tmax).
  float tmax = query.bound(pr.ray);
  auto tmax8 = V8::set1(tmax * Slabs::kPad);
  detail::WideStackItem<Arch> stack[detail::kWideStack];
  int size = 0;
  std::uint32_t ref = start;
  const WideNode<N>* const nodes = bvh.nodes;  // not reloaded after each leaf call
  const Leaves* const all_blocks = bvh.blocks;
  for (;;) {
    if (!(ref & wide_ref::kLeafBit)) {
      query.node();
      const WideNode<N>& node = wide_ref::node_at(nodes, ref);
      // The child references sit on the node's fourth cache line, read only after the slab
      // test: request it now, beside the three lines of boxes.
      __builtin_prefetch(node.child);
      typename V8::V entry;
      detail::ChildHits<Arch> hits = slabs.test(node, tmax8, entry);
      if constexpr (Query::kNearFirst)
        for (std::uint32_t b = hits.bits; b != 0; b &= b - 1)
          if (const std::uint32_t child = node.child[std::countr_zero(b)]; child & wide_ref::kLeafBit)
            wide_ref::request_leaf(all_blocks, child);
      if (hits.bits != 0 && (!Query::kNearFirst || (hits.bits & (hits.bits - 1)) == 0)) {
        // One child entered (the most frequent case), or any order: no distances.
        ref = detail::push_in_slot_order(node, hits, stack, size);
        continue;
      }
      if (hits.bits != 0) {
        ref = detail::push_near_first(node, hits, entry, stack, size);
        continue;
      }
    } else if (const std::uint32_t count = wide_ref::leaf_count(ref); count != 0) {
      // Leaf: its blocks to the query, which may lower tmax or end the walk.
      const detail::LeafStep step = query.leaf(pr, all_blocks + wide_ref::leaf_first(ref), count, tmax);
      if (step == detail::LeafStep::done) return;
      if (step == detail::LeafStep::narrowed) tmax8 = V8::set1(tmax * Slabs::kPad);
    }
    // Pop the next subtree that may still hold a hit nearer than tmax (padded as the
    // exit distance: its entry was computed with rounding).
    for (;;) {
      if (size == 0) return;
      --size;
      if (!Query::kNearFirst || stack[size].entry <= tmax * Slabs::kPad) break;
    }
    ref = stack[size].ref;
  }
}

template <class Arch, TriangleTest Test, bool Robust, int PK>
template <bool SureRange>
detail::RayScreen WideKernels<Arch, Test, Robust, PK>::prepare_single(const Ray& ray, PreparedRay& pr, __m128& inv) {
  // Rejected as by the oracle: non-finite origin or direction, NaN interval ends. The ray's
  // eight floats in two registers: x - x is 0 exactly for finite x (NaN for ±inf, NaN), and
  // the interval ends (lane 3) need only be ordered, so one compare per kind and one blend.
  static_assert(offsetof(Ray, tmin) == 12 && offsetof(Ray, dir) == 16 && offsetof(Ray, tmax) == 28);
  const float* const f = reinterpret_cast<const float*>(&ray);  // org, tmin, dir, tmax
  const __m128 org_tmin = _mm_loadu_ps(f), dir = _mm_loadu_ps(f + 4);
  const __m128 zero = _mm_setzero_ps();
  const __m128 ok_o =
      _mm_blend_ps(_mm_cmpeq_ps(_mm_sub_ps(org_tmin, org_tmin), zero), _mm_cmpord_ps(org_tmin, org_tmin), 0b1000);
  const __m128 ok_d = _mm_blend_ps(_mm_cmpeq_ps(_mm_sub_ps(dir, dir), zero), _mm_cmpord_ps(dir, dir), 0b1000);
  if (_mm_movemask_ps(_mm_and_ps(ok_o, ok_d)) != 0xf) return detail::RayScreen::rejected;
  // The oracle's make_box_ray: reciprocal direction, ±inf for a ±0 component (one division
  // for the three; lane 3 is 1 / tmax, unused).
  inv = _mm_div_ps(_mm_set1_ps(1.0f), dir);
  const auto screened = (_mm_movemask_ps(_mm_cmpeq_ps(dir, zero)) & 0x7) == 0 ? detail::RayScreen::no_zero_component
                                                                              : detail::RayScreen::zero_component;
  pr.ray = ray;
  if constexpr (Test != TriangleTest::watertight) {
    pr.k[0] = pr.k[1] = pr.k[2] = 0;  // (moller and plane need nothing more)
    pr.s[0] = pr.s[1] = pr.s[2] = pr.sure[0] = pr.sure[1] = 0.0f;
  } else {
    // core::make_woop_ray, bit for bit. The axes: core::kWoopAxes at the comparisons of |d|
    // and the signs of d, two compares. The quotients, each one IEEE division: d / d[kz] in
    // one divps, and 1 / d[kz] is inv's lane kz.
    const __m128 a = _mm_andnot_ps(_mm_set1_ps(-0.0f), dir);
    const __m128 ge = _mm_cmpge_ps(_mm_shuffle_ps(a, a, _MM_SHUFFLE(3, 1, 0, 0)),   // |d0| |d0| |d1|
                                   _mm_shuffle_ps(a, a, _MM_SHUFFLE(3, 2, 2, 1)));  // |d1| |d2| |d2|
    const int c = _mm_movemask_ps(ge) & 7;
    const int n = _mm_movemask_ps(_mm_cmplt_ps(dir, zero)) & 7;
    // data()[]: with _GLIBCXX_ASSERTIONS (sanitizer builds) std::array's operator[] is an
    // out-of-line weak function, which a per-ISA object must not define. The index is < 64.
    const int e = core::kWoopAxes.data()[c | n << 3];
    const int kx = e & 3, ky = (e >> 2) & 3, kz = e >> 4;
    alignas(16) float q[4], r[4];
    _mm_store_ps(q, _mm_div_ps(dir, _mm_set1_ps(ray.dir[kz])));
    _mm_store_ps(r, inv);
    pr.k[0] = kx, pr.k[1] = ky, pr.k[2] = kz;
    pr.s[0] = q[kx], pr.s[1] = q[ky], pr.s[2] = r[kz];
    const auto [lo, hi] = SureRange ? core::sure_quotient_range(ray.tmin, ray.tmax) : std::pair{0.0f, 0.0f};
    pr.sure[0] = lo, pr.sure[1] = hi;
  }
  return screened;
}

}  // namespace volley::simd
