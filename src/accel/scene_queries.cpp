// The committed scene's entry points (Accel::Impl::Queries): the layer walk, which answers
// any scene, and the direct forms of a scene that is one wide BVH of triangles, chosen once
// at commit. This file is the only place that asks what a scene holds to pick a query's way.
#include <algorithm>

#include "accel/accel_impl.h"
#include "simd/isa/dispatch.h"

namespace volley {

/// The layers a ray's mask selects, one by one: triangles, then polygons bounded by their
/// hit; the answer attributed, then the instances bounded by it.
struct Accel::Impl::LayerWalk {
  /// The engines' closest hit (prim an internal id) over the layers `mask` selects.
  static void engines_hit(const Impl& s, const Ray& ray, std::uint32_t mask, Hit& hit) {
    for (const Layer& l : s.built.layers) {
      if (!(l.mask & mask)) continue;
      for (const auto& engine : l.engines) engine->intersect(ray, hit);
    }
  }

  static Hit intersect(const Impl& s, const Ray& ray, std::uint32_t mask) {
    Hit hit;
    engines_hit(s, ray, mask, hit);
    s.attribute(hit.prim, hit.geom);
    if (s.built.has_instances) s.intersect_instances(ray, mask, hit);
    return hit;
  }

  /// An instance's hit replaces the engines' one complete (inst set); theirs stays unattributed.
  static void intersect_unmasked(const void* target, const Ray& ray, Hit& hit) {
    const Impl& s = *static_cast<const Impl*>(target);
    engines_hit(s, ray, kMaskAll, hit);
    Hit nearer = hit;
    if (s.built.has_instances && s.intersect_instances(ray, kMaskAll, nearer)) hit = nearer;
  }

  static bool occluded_unmasked(const void* target, const Ray& ray) {
    return occluded(*static_cast<const Impl*>(target), ray, kMaskAll);
  }

  static bool occluded(const Impl& s, const Ray& ray, std::uint32_t mask) {
    for (const Layer& l : s.built.layers) {
      if (!(l.mask & mask)) continue;
      for (const auto& engine : l.engines)
        if (engine->occluded(ray)) return true;
    }
    return s.built.has_instances && s.occluded_instances(ray, mask);
  }

  static Hit intersect_excluding(const Impl& s, const Ray& ray, std::uint32_t mask, std::uint32_t id,
                                 const Hit& excluded) {
    Hit hit;
    for (const Layer& l : s.built.layers) {
      if (!(l.mask & mask)) continue;
      for (const auto& engine : l.engines) engine->intersect_excluding(ray, id, hit);
    }
    s.attribute(hit.prim, hit.geom);
    if (s.built.has_instances) s.intersect_instances(ray, mask, hit, &excluded);
    return hit;
  }

  static bool occluded_excluding(const Impl& s, const Ray& ray, std::uint32_t mask, std::uint32_t id,
                                 const Hit& excluded) {
    for (const Layer& l : s.built.layers) {
      if (!(l.mask & mask)) continue;
      for (const auto& engine : l.engines)
        if (engine->occluded_excluding(ray, id)) return true;
    }
    return s.built.has_instances && s.occluded_instances(ray, mask, &excluded);
  }

  /// A full packet without masks sees every layer (no layer's mask is 0): the caller's
  /// packet goes to each engine as it is. Instances are the caller's (Impl::intersect).
  static void intersect_full(const Impl& s, const RayPacket<16>& rays, HitPacket<16>& hits) {
    for (const Layer& l : s.built.layers)
      for (const auto& engine : l.engines) engine->intersect(rays, hits);
  }

  static std::uint32_t occluded_full(const Impl& s, const RayPacket<16>& rays) {
    std::uint32_t blocked = 0;
    for (const Layer& l : s.built.layers)
      for (const auto& engine : l.engines)
        if ((rays.active & ~blocked) != 0) blocked |= engine->occluded(rays, rays.active & ~blocked);
    return blocked & rays.active;
  }
};

/// One wide BVH of triangles and nothing else (a prototype's usual case): the kernels
/// directly, a layer of calls less per ray.
struct Accel::Impl::WideDirect {
  static Hit intersect(const Impl& s, const Ray& ray, std::uint32_t mask) {
    Hit hit;
    if (s.built.queries.wide_mask & mask) s.built.queries.wide->intersect(ray, hit);
    s.attribute(hit.prim, hit.geom);
    return hit;
  }

  static bool occluded(const Impl& s, const Ray& ray, std::uint32_t mask) {
    return (s.built.queries.wide_mask & mask) && s.built.queries.wide->occluded(ray);
  }

  static Hit intersect_excluding(const Impl& s, const Ray& ray, std::uint32_t mask, std::uint32_t id, const Hit&) {
    Hit hit;
    if (s.built.queries.wide_mask & mask) s.built.queries.wide->intersect(ray, id, hit);
    s.attribute(hit.prim, hit.geom);
    return hit;
  }

  static bool occluded_excluding(const Impl& s, const Ray& ray, std::uint32_t mask, std::uint32_t id, const Hit&) {
    return (s.built.queries.wide_mask & mask) && s.built.queries.wide->occluded(ray, id);
  }

  static void intersect_full(const Impl& s, const RayPacket<16>& rays, HitPacket<16>& hits) {
    s.built.queries.wide->intersect(rays, hits);
  }

  static std::uint32_t occluded_full(const Impl& s, const RayPacket<16>& rays) {
    return s.built.queries.wide->occluded(rays);
  }
};

namespace {

/// The entry points of one way of answering (LayerWalk or WideDirect) into the table.
template <class Forms, class Queries>
void set_forms(Queries& q) {
  q.intersect = &Forms::intersect;
  q.occluded = &Forms::occluded;
  q.intersect_excluding = &Forms::intersect_excluding;
  q.occluded_excluding = &Forms::occluded_excluding;
  q.intersect_full = &Forms::intersect_full;
  q.occluded_full = &Forms::occluded_full;
}

}  // namespace

Accel::Impl::Impl() { choose_queries(); }

void Accel::Impl::choose_queries() {
  Queries q;
  set_forms<LayerWalk>(q);
  q.intersect_unmasked = &LayerWalk::intersect_unmasked;
  q.occluded_unmasked = &LayerWalk::occluded_unmasked;
  q.unmasked_target = this;
  const bool one_engine = built.layers.size() == 1 && built.layers[0].engines.size() == 1 && !built.has_instances;
  q.wide = one_engine ? built.layers[0].engines[0]->wide() : nullptr;
  if (q.wide) {
    q.wide_mask = built.layers[0].mask;
    set_forms<WideDirect>(q);
    const accel::WideAccel::SingleRay& kernels = q.wide->single_ray();
    q.intersect_unmasked = kernels.intersect;
    q.occluded_unmasked = kernels.occluded;
    q.unmasked_target = kernels.bvh;
  }
  q.stream.packets = !built.layers.empty() && (!built.has_instances || built.isa != Isa::scalar) &&
                     std::all_of(built.layers.begin(), built.layers.end(), [](const Layer& l) {
                       return l.engines.empty() ? !l.instances.empty()
                                                : std::any_of(l.engines.begin(), l.engines.end(),
                                                              [](const auto& e) { return e->traces_packets(); });
                     });
  q.stream.mixed_closest = built.has_instances;
  const simd::StreamTraits traits = simd::stream_traits(built.isa);
  q.stream.mixed_any = built.has_instances || traits.unordered_packets;
  q.stream.every_hit_packets = q.stream.packets && !built.has_instances;
  q.stream.probe_batches = q.stream.packets && traits.probe_batches;
  built.queries = q;
}

}  // namespace volley
