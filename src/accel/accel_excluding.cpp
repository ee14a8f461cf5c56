// The excluding queries (Accel::intersect_excluding, occluded_excluding): closest and any
// hit with one primitive left out, named as a hit names it (geometry, primitive, instance).
// A ray that leaves a surface passes over the triangle it starts on by its id, so it needs
// no offset of its origin (an epsilon that is too small for far scenes and too large for
// thin features). The engines pass over the primitive's internal id; an instance's
// prototype passes over it only for the rays carried through that instance.
#include <algorithm>
#include <string>
#include <vector>

#include "accel/accel_impl.h"

namespace volley {

std::uint32_t Accel::Impl::excluded_id(const char* caller, const Hit& excluded) const {
  if (excluded.prim == kInvalidPrim) return kInvalidPrim;  // a miss excludes nothing
  if (excluded.inst == kInvalidId && excluded.geom < added.geometries.size()) {  // the common case, once per ray
    const Geometry& g = added.geometries[excluded.geom];
    if (g.kind != Kind::instance && excluded.prim < g.count) return g.first + excluded.prim;
  }
  return excluded_elsewhere(caller, excluded);
}

std::uint32_t Accel::Impl::excluded_elsewhere(const char* caller, const Hit& excluded) const {
  const auto where = [caller] { return std::string(caller) + ": the excluded hit's "; };
  if (excluded.inst != kInvalidId) {
    if (excluded.inst >= added.geometries.size() || added.geometries[excluded.inst].kind != Kind::instance)
      throw Error(where() + "inst " + std::to_string(excluded.inst) + " is not an instance of this scene");
    Hit inner = excluded;
    inner.inst = kInvalidId;
    added.instances[added.geometries[excluded.inst].index].prototype->excluded_id(caller, inner);
    return kInvalidPrim;  // not one of this scene's own primitives
  }
  if (excluded.geom >= added.geometries.size() || added.geometries[excluded.geom].kind == Kind::instance)
    throw Error(where() + "geom " + std::to_string(excluded.geom) + " is not a triangle or polygon geometry of this " +
                "scene (" + std::to_string(added.geometries.size()) + " geometry ids)");
  const Geometry& g = added.geometries[excluded.geom];
  if (excluded.prim >= g.count)
    throw Error(where() + "prim " + std::to_string(excluded.prim) + " is not in geometry " +
                std::to_string(excluded.geom) + " (" + std::to_string(g.count) + " primitives)");
  return g.first + excluded.prim;
}

Hit Accel::Impl::intersect_excluding(const Ray& ray, std::uint32_t mask, const Hit& excluded) const {
  return built.queries.intersect_excluding(*this, ray, mask, excluded_id("intersect_excluding", excluded), excluded);
}

bool Accel::Impl::occluded_excluding(const Ray& ray, std::uint32_t mask, const Hit& excluded) const {
  return built.queries.occluded_excluding(*this, ray, mask, excluded_id("occluded_excluding", excluded), excluded);
}

Hit Accel::intersect_excluding(const Ray& ray, const Hit& excluded, std::uint32_t mask) const {
  if (!impl_->built.committed) throw Error("intersect_excluding: call commit() after adding geometry");
  return impl_->intersect_excluding(ray, mask, excluded);
}

bool Accel::occluded_excluding(const Ray& ray, const Hit& excluded, std::uint32_t mask) const {
  if (!impl_->built.committed) throw Error("occluded_excluding: call commit() after adding geometry");
  return impl_->occluded_excluding(ray, mask, excluded);
}

bool Accel::Impl::excluding_stream(const QueryArguments& args, std::size_t count) const {
  if (!built.queries.wide || count < kStreamWalkRays) return false;
  if (args.masks)
    for (std::size_t i = 0; i < count; ++i)
      if (!(args.masks[i] & built.queries.wide_mask)) return false;
  return true;
}

void Accel::Impl::intersect_excluding(const Ray* rays, const QueryArguments& args, const std::uint32_t* ids,
                                      std::size_t count, Hit* hits) const {
  if (excluding_stream(args, count)) {
    std::fill(hits, hits + count, Hit{});
    built.queries.wide->intersect(rays, count, ids, hits);
    for (std::size_t i = 0; i < count; ++i) attribute(hits[i].prim, hits[i].geom);
    return;
  }
  for (std::size_t i = 0; i < count; ++i)
    hits[i] = built.queries.intersect_excluding(*this, rays[i], args.masks ? args.masks[i] : kMaskAll, ids[i],
                                                args.excluded[i]);
}

void Accel::Impl::occluded_excluding(const Ray* rays, const QueryArguments& args, const std::uint32_t* ids,
                                     std::size_t count, std::uint8_t* blocked) const {
  if (excluding_stream(args, count)) {
    built.queries.wide->occluded(rays, count, ids, blocked);
    return;
  }
  for (std::size_t i = 0; i < count; ++i)
    blocked[i] = built.queries.occluded_excluding(*this, rays[i], args.masks ? args.masks[i] : kMaskAll, ids[i],
                                                  args.excluded[i])
                     ? 1
                     : 0;
}

std::vector<std::uint32_t> Accel::Impl::excluded_ids(const char* caller, const Hit* excluded,
                                                     std::size_t count) const {
  std::vector<std::uint32_t> ids(count);
  for (std::size_t i = 0; i < count; ++i) {
    try {
      ids[i] = excluded_id(caller, excluded[i]);
    } catch (const Error& e) {
      throw Error(std::string(e.what()) + " (excluded[" + std::to_string(i) + "])");
    }
  }
  return ids;
}

}  // namespace volley
