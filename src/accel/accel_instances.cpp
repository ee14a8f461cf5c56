// Instances (Accel::add_instance): committed Accels placed under affine transforms. Each
// layer holds a wide BVH over its instances' world boxes (instance_tree.h); a ray walks it after the
// layer's own triangles and polygons, is carried into each instance's object space met on
// the way and queried against the prototype there, bounded by the nearest hit so far.
#include <immintrin.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <string>

#include "accel/accel_impl.h"
#include "core/rounding.h"

namespace volley {
namespace {

/// x' = M x + (translation if point): M as 12 floats [A | t] row by row.
glm::vec3 apply(const float* m, const float* x, bool point) {
  glm::vec3 out;
  for (int r = 0; r < 3; ++r)
    out[r] = m[4 * r] * x[0] + m[4 * r + 1] * x[1] + m[4 * r + 2] * x[2] + (point ? m[4 * r + 3] : 0.0f);
  return out;
}

/// The inverse of [A | t] (in double, rounded once), or false when A is singular.
bool invert(const float* m, float* out) {
  double a[3][3];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) a[r][c] = m[4 * r + c];
  const double det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
                     a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                     a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
  if (!(std::fabs(det) > 0.0) || !std::isfinite(det)) return false;
  double inv[3][3];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      // Cofactor of a[c][r] over det (the adjugate's transpose).
      const int r1 = (c + 1) % 3, r2 = (c + 2) % 3, c1 = (r + 1) % 3, c2 = (r + 2) % 3;
      inv[r][c] = (a[r1][c1] * a[r2][c2] - a[r1][c2] * a[r2][c1]) / det;
    }
  for (int r = 0; r < 3; ++r) {
    double t = 0.0;
    for (int c = 0; c < 3; ++c) {
      out[4 * r + c] = static_cast<float>(inv[r][c]);
      t -= inv[r][c] * m[4 * c + 3];
    }
    out[4 * r + 3] = static_cast<float>(t);
  }
  for (int k = 0; k < 12; ++k)
    if (!std::isfinite(out[k])) return false;
  return true;
}

/// The world box of an instance: every corner of its prototype's bound parts transformed.
core::BBox world_box(const std::vector<core::BBox>& parts, const float* to_world) {
  core::BBox out;
  for (const core::BBox& b : parts) {
    if (!(b.lo.x <= b.hi.x)) continue;
    for (int corner = 0; corner < 8; ++corner) {
      const float p[3] = {corner & 1 ? b.hi.x : b.lo.x, corner & 2 ? b.hi.y : b.lo.y, corner & 4 ? b.hi.z : b.lo.z};
      out.extend(apply(to_world, p, true));
    }
  }
  // Widened by the rounding of the corners' transform and of the ray's into object space,
  // so that no ray the prototype would hit is culled at the box's faces.
  if (out.lo.x <= out.hi.x) {
    const float size = std::max({glm::length(out.lo), glm::length(out.hi)});
    const float pad = core::rounding_gamma(16) * size;
    out.lo -= glm::vec3(pad), out.hi += glm::vec3(pad);
  }
  return out;
}

}  // namespace

std::uint32_t Accel::add_instance(const Accel& prototype, const float* transform) {
  if (!transform) throw Error("add_instance: transform is null (12 floats expected)");
  const std::shared_ptr<Impl>& proto = prototype.impl_;
  if (!proto) throw Error("add_instance: the prototype was moved from");
  if (proto == impl_) throw Error("add_instance: an Accel cannot instance itself");
  if (!proto->built.committed) throw Error("add_instance: commit the prototype first");
  if (!proto->added.instances.empty())
    throw Error("add_instance: the prototype holds instances itself (instances are one level deep)");
  for (int k = 0; k < 12; ++k)
    if (!std::isfinite(transform[k]))
      throw Error("add_instance: transform entry " + std::to_string(k) + " (row " + std::to_string(k / 4) +
                  ", column " + std::to_string(k % 4) + ") is not finite");
  Impl::Instance instance;
  std::memcpy(instance.to_world, transform, sizeof instance.to_world);
  if (!invert(transform, instance.to_object))
    throw Error("add_instance: the transform's 3x3 part is singular (it has no inverse)");
  instance.prototype = proto;
  const std::uint32_t id = impl_->new_geometry(0, Impl::Kind::instance);
  instance.geometry = id;
  impl_->added.instances.push_back(std::move(instance));
  return id;
}

void Accel::Impl::compute_bound_parts() {
  // Where every layer is a wide BVH of triangles alone: the used children of its root.
  built.bound_parts.clear();
  bool wide = !built.layers.empty();
  for (const Layer& l : built.layers) {
    const accel::WideAccel* w = l.triangle_engine ? l.triangle_engine->wide() : nullptr;
    const accel::WideImage image = w ? w->image() : accel::WideImage{};
    if (!w || l.engines.size() != 1 || !l.instances.empty() || (image.root & simd::wide_ref::kLeafBit)) {
      wide = false;
      break;
    }
    const auto& root = *static_cast<const simd::WideNode<simd::kWideN>*>(image.nodes);
    for (int c = 0; c < simd::kWideN; ++c) {
      const core::BBox b = simd::slot_box(root, c);
      if (b.lo.x <= b.hi.x && b.lo.y <= b.hi.y && b.lo.z <= b.hi.z) built.bound_parts.push_back(b);
    }
  }
  if (wide) return;
  // Otherwise one box of every vertex added (conservative).
  core::BBox all;
  if (mapped.packed) {
    const std::span<const float> v = mapped.packed->vertices;
    for (std::size_t i = 0; i + 2 < v.size(); i += 3) all.extend(glm::vec3(v[i], v[i + 1], v[i + 2]));
  } else {
    for (const glm::vec3& p : added.triangles) all.extend(p);
  }
  for (const core::Polygon& poly : added.polygons)
    for (const auto& p : poly.vertices) all.extend(p);
  built.bound_parts = {all};
}

void Accel::Impl::build_instances() {
  built.has_instances = false;
  for (Layer& layer : built.layers) {
    layer.instances.clear();
    std::vector<core::BBox> boxes;
    for (const Geometry& g : added.geometries) {
      if (g.kind != Kind::instance || !g.enabled || g.mask != layer.mask) continue;
      const Instance& in = added.instances[g.index];
      InstanceSlot slot;
      for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) slot.object_columns[c][r] = r < 3 ? in.to_object[4 * r + c] : 0.0f;
      slot.prototype = in.prototype.get();
      slot.geometry = in.geometry;
      layer.instances.push_back(slot);
      boxes.push_back(world_box(in.prototype->built.bound_parts, in.to_world));
    }
    layer.instance_tree.build(boxes, built.isa, built.robust);
    built.has_instances |= !layer.instances.empty();
  }
}

namespace {

/// The ray in an instance's object space over [ray.tmin, tmax): same t (the direction is
/// not normalised). As apply() with to_object, bit for bit (the same sums in the same order:
/// ((x m0 + y m1) + z m2) + m3, the direction's + 0), three rows at once. Written as two
/// 16-byte stores: the prototype's walk loads it so right away, and a load that needs
/// several smaller stores cannot be forwarded from them (it waits for them to retire).
[[gnu::always_inline]] inline Ray to_object(const float (&columns)[4][4], const Ray& ray, float tmax) {
  const __m128 c0 = _mm_load_ps(columns[0]), c1 = _mm_load_ps(columns[1]), c2 = _mm_load_ps(columns[2]);
  const __m128 o = _mm_add_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(c0, _mm_set1_ps(ray.org[0])),
                                                    _mm_mul_ps(c1, _mm_set1_ps(ray.org[1]))),
                                         _mm_mul_ps(c2, _mm_set1_ps(ray.org[2]))),
                              _mm_load_ps(columns[3]));
  const __m128 d = _mm_add_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(c0, _mm_set1_ps(ray.dir[0])),
                                                    _mm_mul_ps(c1, _mm_set1_ps(ray.dir[1]))),
                                         _mm_mul_ps(c2, _mm_set1_ps(ray.dir[2]))),
                              _mm_setzero_ps());
  // Lane 3 of each: tmin, tmax ([x y z z] then [x y z t] by two shuffles).
  const __m128 ot = _mm_shuffle_ps(o, _mm_set1_ps(ray.tmin), _MM_SHUFFLE(0, 0, 2, 2));
  const __m128 dt = _mm_shuffle_ps(d, _mm_set1_ps(tmax), _MM_SHUFFLE(0, 0, 2, 2));
  static_assert(offsetof(Ray, tmin) == 12 && offsetof(Ray, dir) == 16 && offsetof(Ray, tmax) == 28);
  Ray out;
  _mm_storeu_ps(reinterpret_cast<float*>(&out), _mm_shuffle_ps(o, ot, _MM_SHUFFLE(2, 0, 1, 0)));
  _mm_storeu_ps(reinterpret_cast<float*>(&out) + 4, _mm_shuffle_ps(d, dt, _MM_SHUFFLE(2, 0, 1, 0)));
  return out;
}

}  // namespace

namespace {

/// The excluding queries' primitive as the prototype of instance `geometry` names it, or
/// null when it lies elsewhere.
const Hit* excluded_in(const Hit* excluded, std::uint32_t geometry, Hit& inner) {
  if (!excluded || excluded->inst != geometry) return nullptr;
  inner = *excluded;
  inner.inst = kInvalidId;
  return &inner;
}

/// Instance `in`'s answer for a world-space ray: its prototype asked in object space up
/// to `bound`, skipping `excluded` where that lies inside this instance.
template <bool AnyHit, class Slot>
auto query_instance(const Slot& in, const Ray& ray, float bound, std::uint32_t mask, const Hit* excluded) {
  const Ray local = to_object(in.object_columns, ray, bound);
  Hit inner;
  const Hit* skip = excluded_in(excluded, in.geometry, inner);
  if constexpr (AnyHit)
    return skip ? in.prototype->occluded_excluding(local, mask, *skip) : in.prototype->occluded(local, mask);
  else
    return skip ? in.prototype->intersect_excluding(local, mask, *skip) : in.prototype->intersect(local, mask);
}

}  // namespace

bool Accel::Impl::intersect_instances(const Ray& ray, std::uint32_t mask, Hit& hit, const Hit* excluded) const {
  bool found = false;
  for (const Layer& l : built.layers) {
    if (!(l.mask & mask) || l.instances.empty()) continue;
    auto leaf = [&](std::uint32_t k, float& bound) {
      Hit h = query_instance<false>(l.instances[k], ray, bound, mask, excluded);
      if (!h.hit()) return false;
      bound = h.t;
      h.inst = l.instances[k].geometry;
      hit = h;
      found = true;
      return true;
    };
    l.instance_tree.walk(simd::InstanceWalk::closest, ray, hit.t, leaf);
  }
  return found;
}

bool Accel::Impl::occluded_instances(const Ray& ray, std::uint32_t mask, const Hit* excluded) const {
  for (const Layer& l : built.layers) {
    if (!(l.mask & mask) || l.instances.empty()) continue;
    auto leaf = [&](std::uint32_t k, float& bound) {
      return query_instance<true>(l.instances[k], ray, bound, mask, excluded);
    };
    if (l.instance_tree.walk(simd::InstanceWalk::any, ray, ray.tmax, leaf)) return true;
  }
  return false;
}

void Accel::Impl::all_hits_instances(const Ray& ray, std::uint32_t mask, std::vector<Hit>& out) const {
  for (const Layer& l : built.layers) {
    if (!(l.mask & mask) || l.instances.empty()) continue;
    auto leaf = [&](std::uint32_t k, float&) {
      const InstanceSlot& in = l.instances[k];
      const std::size_t first = out.size();
      in.prototype->all_hits(to_object(in.object_columns, ray, ray.tmax), mask, out);
      for (std::size_t i = first; i < out.size(); ++i) out[i].inst = in.geometry;
      return false;
    };
    l.instance_tree.walk(simd::InstanceWalk::every, ray, ray.tmax, leaf);
  }
}

// Packets: the top level is walked by the packet, and the lanes that reach an instance go
// through its prototype one by one (querying the prototype as a packet when all 16 lanes
// reached it was 3-5% slower on Zen 5, no faster on Sapphire Rapids: perf/reports/instances.md).

namespace {

/// The lanes `lanes` of `world` in an instance's object space, lane i bounded by bound[i],
/// all of them before the first prototype walk: each lane's transform then no longer sits
/// between the previous lane's walk and its own (instanced packets 5-10% faster).
void to_object(const float (&columns)[4][4], const RayPacket<16>& world, const float* bound, std::uint32_t lanes,
               Ray* local) {
  for (std::uint32_t b = lanes; b != 0; b &= b - 1) {
    const int i = __builtin_ctz(b);
    local[i] = to_object(columns, accel::lane_ray(world, i), bound[i]);
  }
}

}  // namespace

void Accel::Impl::intersect_instances(RayPacket<16>& world, const std::uint32_t* masks, HitPacket<16>& hits) const {
  const std::uint32_t active = world.active;
  for (const Layer& l : built.layers) {
    const std::uint32_t lanes = lanes_of(active, masks, l.mask);
    if (lanes == 0 || l.instances.empty()) continue;
    world.active = lanes;
    // Each lane bounded by its hit so far (an earlier layer's included: hits.t only falls).
    for (std::uint32_t b = lanes; b != 0; b &= b - 1) {
      const int i = __builtin_ctz(b);
      world.tmax[i] = std::min(world.tmax[i], hits.t[i]);
    }
    auto leaf = [&](std::uint32_t k, std::uint32_t in_lanes, float* bound) {
      const InstanceSlot& in = l.instances[k];
      std::uint32_t found = 0;
      auto keep = [&](int i, Hit h) {
        bound[i] = h.t;
        h.inst = in.geometry;
        set_hit(hits, i, h);
        found |= 1u << i;
      };
      Ray local[16];
      to_object(in.object_columns, world, bound, in_lanes, local);
      for (std::uint32_t b = in_lanes; b != 0; b &= b - 1) {
        const int i = __builtin_ctz(b);
        const Hit h = in.prototype->intersect(local[i], masks ? masks[i] : kMaskAll);
        if (h.hit()) keep(i, h);
      }
      return found;
    };
    l.instance_tree.walk_packet(simd::InstanceWalk::closest, world, leaf);
  }
}

std::uint32_t Accel::Impl::occluded_instances(RayPacket<16>& world, const std::uint32_t* masks) const {
  const std::uint32_t active = world.active;
  std::uint32_t blocked = 0;
  for (const Layer& l : built.layers) {
    const std::uint32_t lanes = lanes_of(active & ~blocked, masks, l.mask);
    if (lanes == 0 || l.instances.empty()) continue;
    world.active = lanes;
    auto leaf = [&](std::uint32_t k, std::uint32_t in_lanes, float* bound) {
      const InstanceSlot& in = l.instances[k];
      Ray local[16];
      to_object(in.object_columns, world, bound, in_lanes, local);
      std::uint32_t found = 0;
      for (std::uint32_t b = in_lanes; b != 0; b &= b - 1) {
        const int i = __builtin_ctz(b);
        if (in.prototype->occluded(local[i], masks ? masks[i] : kMaskAll)) found |= 1u << i;
      }
      return found;
    };
    blocked |= l.instance_tree.walk_packet(simd::InstanceWalk::any, world, leaf);
  }
  return blocked;
}

}  // namespace volley
