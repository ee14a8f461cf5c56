// The single-ray walk of the wide BVH: the entry prepares the ray itself (screen,
// reciprocal, the watertight shear), then an explicit stack, children sorted by entry
// distance when the query asks for it, leaves handed to the query (queries.h), whose
// block kernels are inlined into the walk.
#pragma once
#include <immintrin.h>

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "simd/wide/node_lanes.h"
#include "simd/wide/queries.h"
#include "simd/wide/stack.h"

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
  using V8 = detail::Lanes8<Arch>;
  static_assert(N == 8, "the single-ray node test reads eight children");
  const Ray& ray = pr.ray;
  // The octant by the sign bit of the reciprocal; near plane of axis a is bounds[2a + neg],
  // far the other.
  const int negative = _mm_movemask_ps(inv);
  // The planes as byte offsets into a node's boxes: an address is then the node plus an
  // offset, with no index to widen and scale at every node.
  std::size_t near_plane[3];
  for (int a = 0; a < 3; ++a) near_plane[a] = (2 * a + ((negative >> a) & 1)) * sizeof(WideNode<N>::bounds[0]);
  constexpr std::size_t kFarPlane = sizeof(WideNode<N>::bounds[0]);  // a far plane's offset from its near one
  const std::size_t nx = near_plane[0], ny = near_plane[1], nz = near_plane[2];
  const std::size_t fx = nx ^ kFarPlane, fy = ny ^ kFarPlane, fz = nz ^ kFarPlane;
  const auto plane = [](const WideNode<N>& node, std::size_t offset) {
    return reinterpret_cast<const float*>(reinterpret_cast<const unsigned char*>(node.bounds) + offset);
  };
  const auto ox = V8::set1(ray.org[0]), oy = V8::set1(ray.org[1]), oz = V8::set1(ray.org[2]);
  const auto ix = V8::template lane<0>(inv), iy = V8::template lane<1>(inv), iz = V8::template lane<2>(inv);
  const auto tmin = V8::set1(ray.tmin);
  const float pad1 = Robust ? core::kSlabExitPad : 1.0f;
  // Far distances use the reciprocal times the exit padding, rounded once per ray:
  // fl(d * fl(inv * pad)) carries the same (1 + eps)^2 bound around d * inv * pad as the
  // oracle's fl(fl(d * inv) * pad), so the 2 gamma(3) margin still covers the rounding of
  // both ends (the padding was sized for the sub, reciprocal and product roundings), and
  // the node test loses a multiply from its longest dependency chain. ±inf stays ±inf.
  const __m128 finv = _mm_mul_ps(inv, _mm_set1_ps(pad1));
  const auto fix = V8::template lane<0>(finv), fiy = V8::template lane<1>(finv), fiz = V8::template lane<2>(finv);
  // With FMA and no zero direction component, a slab distance is one fused operation,
  // b inv - c, where c is org inv rounded outwards (up for near planes, down for far ones)
  // once per ray. Against (b - org) inv that moves near distances down and far ones up by a
  // few ulps of org inv, and rounds once instead of twice, so the padding that covers the
  // two-rounding form covers it (never culls a box the exact ray meets). NaN (inf - inf,
  // only for a subnormal direction component, whose reciprocal overflows) is dropped by
  // max/min as in the other form.
  constexpr bool kFused = NoZero && V8::kFma;
  typename V8::V cnx{}, cny{}, cnz{}, cfx{}, cfy{}, cfz{};
  if constexpr (kFused) {
    // c = p +- (|p| 2^-22 + 2^-149) with p = fl(org inv): p is within 2^-24 |org inv| of the
    // exact product (2^-150 if subnormal), so the widened c lies beyond it even after its
    // own rounding. Three lanes at once; an infinite p gives +inf or NaN, both harmless.
    const __m128 org = _mm_loadu_ps(ray.org), sign = _mm_set1_ps(-0.0f);
    // (Robust = false: c = p, no widening, as it has no padding.)
    const __m128 rel = _mm_set1_ps(Robust ? 0x1p-22f : 0.0f), tiny = _mm_set1_ps(Robust ? 0x1p-149f : 0.0f);
    const __m128 pn = _mm_mul_ps(org, inv);
    const __m128 pf = _mm_mul_ps(org, finv);
    const __m128 cn = _mm_add_ps(pn, _mm_add_ps(_mm_mul_ps(_mm_andnot_ps(sign, pn), rel), tiny));
    const __m128 cf = _mm_sub_ps(pf, _mm_add_ps(_mm_mul_ps(_mm_andnot_ps(sign, pf), rel), tiny));
    cnx = V8::template lane<0>(cn), cny = V8::template lane<1>(cn), cnz = V8::template lane<2>(cn);
    cfx = V8::template lane<0>(cf), cfy = V8::template lane<1>(cf), cfz = V8::template lane<2>(cf);
  }

  // The upper end of the search (closest hit, as RayBlockKernels: the nearer of hit.t and tmax).
  float tmax = query.bound(ray);
  auto tmax8 = V8::set1(tmax * pad1);
  detail::WideStackItem<Arch> stack[detail::kWideStack];
  int size = 0;
  std::uint32_t ref = start;
  const WideNode<N>* const nodes = bvh.nodes;  // not reloaded after each leaf call
  const Leaves* const all_blocks = bvh.blocks;
  for (;;) {
    if (!(ref & wide_ref::kLeafBit)) {
      // Interior: slab test of all eight children at once.
      query.node();
      const WideNode<N>& node = wide_ref::node_at(nodes, ref);
      // The child references sit on the node's fourth cache line, read only after the slab
      // test: request it now, beside the three lines of boxes.
      _mm_prefetch(reinterpret_cast<const char*>(node.child), _MM_HINT_T0);
      typename V8::V tnx, tny, tnz, tfx, tfy, tfz;
      if constexpr (kFused) {
        tnx = V8::fmsub(V8::load(plane(node, nx)), ix, cnx);
        tny = V8::fmsub(V8::load(plane(node, ny)), iy, cny);
        tnz = V8::fmsub(V8::load(plane(node, nz)), iz, cnz);
        tfx = V8::fmsub(V8::load(plane(node, fx)), fix, cfx);
        tfy = V8::fmsub(V8::load(plane(node, fy)), fiy, cfy);
        tfz = V8::fmsub(V8::load(plane(node, fz)), fiz, cfz);
      } else {
        tnx = V8::mul(V8::sub(V8::load(plane(node, nx)), ox), ix);
        tny = V8::mul(V8::sub(V8::load(plane(node, ny)), oy), iy);
        tnz = V8::mul(V8::sub(V8::load(plane(node, nz)), oz), iz);
        tfx = V8::mul(V8::sub(V8::load(plane(node, fx)), ox), fix);
        tfy = V8::mul(V8::sub(V8::load(plane(node, fy)), oy), fiy);
        tfz = V8::mul(V8::sub(V8::load(plane(node, fz)), oz), fiz);
      }
      typename V8::V entry, exit;
      if constexpr (NoZero) {
        // Combined as a tree. No direction component is ±0, but a subnormal one has an
        // infinite reciprocal, so a distance can still be NaN (origin on the plane). The tree
        // stays NaN-free: tmin / tmax8 are never NaN, so the right halves are not; a NaN left
        // half then yields the right one. A NaN drops its partner distance too, which only
        // lowers entry or raises exit: more boxes visited, never fewer (tests/accel:
        // subnormal directions).
        entry = V8::max(V8::max(tnx, tny), V8::max(tnz, tmin));
        exit = V8::min(V8::min(tfx, tfy), V8::min(tfz, tmax8));
      } else {
        entry = V8::max(tnz, V8::max(tny, V8::max(tnx, tmin)));
        exit = V8::min(tfz, V8::min(tfy, V8::min(tfx, tmax8)));
      }
      // The hit children as bits, and the first one's reference. AVX-512 compares into a
      // mask register and takes the reference out of the node's reference vector with one
      // vpcompressd, so the next node's address does not wait for movemask, bit scan and a
      // load indexed by it, the longest chain of the walk (perf/traversal.md).
      std::uint32_t bits;
      std::uint32_t first_ref = 0;
      [[maybe_unused]] __mmask8 k = 0;  // AVX-512: the hit mask and the node's references
      [[maybe_unused]] __m256i refs;
      if constexpr (detail::kHasMaskRegisters<Arch>) {
        k = _mm256_cmp_ps_mask(entry, exit, _CMP_LE_OQ);
        bits = k;
        refs = _mm256_load_si256(reinterpret_cast<const __m256i*>(node.child));
        first_ref =
            static_cast<std::uint32_t>(_mm_cvtsi128_si32(_mm256_castsi256_si128(_mm256_maskz_compress_epi32(k, refs))));
      } else {
        bits = V8::le(entry, exit);
        if (bits) first_ref = node.child[std::countr_zero(bits)];
      }
      if constexpr (Query::kNearFirst)
        for (std::uint32_t b = bits; b != 0; b &= b - 1)
          if (const std::uint32_t child = node.child[std::countr_zero(b)]; child & wide_ref::kLeafBit)
            wide_ref::request_leaf(all_blocks, child);
      if (!Query::kNearFirst && bits != 0) {
        // Any order: no ordering and no distances (the stack entries are never pruned): the
        // first hit child next, the others on the stack.
        ref = first_ref;
        for (bits &= bits - 1; bits != 0; bits &= bits - 1) stack[size++].ref = node.child[std::countr_zero(bits)];
        continue;
      }
      if (bits != 0) {
        const int i = std::countr_zero(bits);
        bits &= bits - 1;
        if (bits == 0) {
          ref = first_ref;
          continue;
        }
        alignas(32) float dist[8];
        V8::store(dist, entry);
        const int j = std::countr_zero(bits);
        bits &= bits - 1;
        if (bits == 0) {
          // Two children: the nearer next, the other on the stack (selects, not a branch:
          // which one is nearer is a coin toss to the predictor).
          std::uint32_t ci, cj;
          float di, dj;
          if constexpr (detail::kHasMaskRegisters<Arch>) {
            // Both distances and the second reference compressed from registers too, not
            // reloaded from the stored distances.
            const __m128 d = _mm256_castps256_ps128(_mm256_maskz_compress_ps(k, entry));
            ci = first_ref;
            cj = static_cast<std::uint32_t>(
                _mm_extract_epi32(_mm256_castsi256_si128(_mm256_maskz_compress_epi32(k, refs)), 1));
            di = _mm_cvtss_f32(d);
            dj = _mm_cvtss_f32(_mm_movehdup_ps(d));
          } else {
            ci = node.child[i], cj = node.child[j];
            di = dist[i], dj = dist[j];
          }
          const bool swap = dj < di;
          stack[size++] = {swap ? ci : cj, swap ? di : dj};
          ref = swap ? cj : ci;
          continue;
        }
        if (std::popcount(bits) <= 2) {
          // Three or four (most nodes with three or more hit children): sorted in registers
          // by a stable network of compare-exchanges, the nearest reference never stored and
          // reloaded as in the insertion sort below. GCC compiles each exchange to a short
          // branch; branch-free, the nearest would wait for every exchange (the variants
          // measured: perf/traversal.md).
          std::uint64_t w[4] = {detail::stack_word(node.child[i], dist[i]), detail::stack_word(node.child[j], dist[j]),
                                0, 0};
          const int k = std::countr_zero(bits);
          w[2] = detail::stack_word(node.child[k], dist[k]);
          bits &= bits - 1;
          int n = 3;
          if (bits == 0) {
            detail::sort_far_first<3>(w);
          } else {
            const int l = std::countr_zero(bits);
            w[3] = detail::stack_word(node.child[l], dist[l]);
            detail::sort_far_first<4>(w);
            n = 4;
          }
          std::memcpy(&stack[size], w, 8 * static_cast<std::size_t>(n - 1));
          size += n - 1;
          ref = static_cast<std::uint32_t>(w[n - 1]);
          continue;
        }
        // Five or more: push all, sort the pushed run far to near (insertion sort of at
        // most eight), and continue with the nearest (the top).
        const int base = size;
        stack[size++] = {node.child[i], dist[i]};
        stack[size++] = {node.child[j], dist[j]};
        for (; bits != 0; bits &= bits - 1) {
          const int k = std::countr_zero(bits);
          stack[size++] = {node.child[k], dist[k]};
        }
        for (int a = base + 1; a < size; ++a) {
          const detail::WideStackItem<Arch> item = stack[a];
          int b = a;
          for (; b > base && stack[b - 1].entry < item.entry; --b) stack[b] = stack[b - 1];
          stack[b] = item;
        }
        ref = stack[--size].ref;
        continue;
      }
    } else {
      // Leaf: its blocks to the query, which may lower tmax or end the walk.
      const std::uint32_t count = wide_ref::leaf_count(ref);
      if (count != 0) {
        const detail::LeafStep step = query.leaf(pr, all_blocks + wide_ref::leaf_first(ref), count, tmax);
        if (step == detail::LeafStep::done) return;
        if (step == detail::LeafStep::narrowed) tmax8 = V8::set1(tmax * pad1);
      }
    }
    // Pop the next subtree that may still hold a hit nearer than tmax (padded as the
    // exit distance: its entry was computed with rounding).
    for (;;) {
      if (size == 0) return;
      --size;
      if (!Query::kNearFirst || stack[size].entry <= tmax * pad1) break;
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
