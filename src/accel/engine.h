// The engines behind Accel: each answers the queries over one kind of primitive in one
// way. Triangles have three: the wide SIMD BVH (wide_engine.cpp), the scalar oracle in
// float (oracle_engine.cpp) and the accuracy reference in double (reference_engine.cpp);
// polygons one (polygon_engine.cpp). At commit Accel::Impl gives each layer one engine per
// kind it holds (Layer::engines: triangles first, then polygons bounded by their hit).
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "core/bvh.h"
#include "core/point_triangle.h"
#include "core/polygon.h"
#include "volley/accel.h"
#include "volley/options.h"
#include "volley/packet.h"
#include "volley/ray.h"

namespace volley::accel {

class WideAccel;

/// One kind of primitive behind its own BVH. Built before its first query, then immutable:
/// every query is const and thread-safe.
class Engine {
 public:
  virtual ~Engine() = default;
  /// Closest hit with tmin <= t < min(hit.t, ray.tmax): updates `hit`, true when it found one.
  virtual bool intersect(const Ray& ray, Hit& hit) const = 0;
  /// Whether something is hit with tmin <= t < tmax.
  virtual bool occluded(const Ray& ray) const = 0;
  /// The two above with the primitive of id `excluded` left out (kInvalidPrim: none): the
  /// answers over the same structure without it (Accel::intersect_excluding).
  virtual bool intersect_excluding(const Ray& ray, std::uint32_t excluded, Hit& hit) const = 0;
  virtual bool occluded_excluding(const Ray& ray, std::uint32_t excluded) const = 0;
  /// Closest hits of the active lanes (hits.t bounds each lane like tmax; only lanes with a
  /// nearer hit are written). Inactive lanes are inert (Accel::Impl widens a caller's packet
  /// with inactive lanes into a copy). The default answers lane by lane.
  virtual void intersect(const RayPacket<16>& rays, HitPacket<16>& hits) const;
  /// The lanes of `lanes` (active ones) that something occludes. Lane by lane by default.
  virtual std::uint32_t occluded(const RayPacket<16>& rays, std::uint32_t lanes) const;
  /// Every hit with tmin <= t < tmax, appended to `out` (prim = the engine's id), by the
  /// crossing rule where the test has one (the watertight test: each crossing of a closed
  /// mesh once, docs/crossings.md).
  virtual void all_hits(const Ray& ray, std::vector<Hit>& out) const = 0;
  /// The same for the active lanes of a packet, lane i's into out[i]. Lane by lane by default.
  virtual void all_hits(const RayPacket<16>& rays, std::vector<Hit>* out) const;
  /// Offers the engine's primitives to a point query: updates `query` with a nearer one.
  virtual void closest_point(core::PointQuery& query) const = 0;
  /// Whether packets are traced as packets, not lane by lane (the stream policy packs rays
  /// into packets only then).
  virtual bool traces_packets() const { return false; }
  /// Adds the engine's structure (nodes, leaves, depth, bytes) to `info`.
  virtual void describe(AccelInfo& info) const = 0;
  /// The wide BVH when this is the SIMD triangle engine: a scene that is this engine alone
  /// calls its kernels directly (Accel::Impl::Queries).
  virtual const WideAccel* wide() const { return nullptr; }
};

/// The triangles of a scene, in prim-id order (borrowed: Accel::Impl keeps them, and adding
/// geometry uncommits the Accel, so no query reads them after they change).
struct Triangles {
  const glm::vec3* vertices;      ///< 3 per triangle
  const std::uint32_t* ids;
  std::size_t count;
  const unsigned char* excluded;  ///< 1 per triangle: 1 = left out of the BVH (degenerate or disabled)
};

/// An engine over triangles: Accel::Impl builds the binary BVH it asks for over the
/// triangles' boxes (degenerate triangles get empty boxes) and hands it over.
class TriangleEngine : public Engine {
 public:
  /// The binary BVH's build options (leaf sizes and costs suited to this engine).
  virtual core::BvhBuildOptions bvh_options() const = 0;
  /// Takes the BVH over `triangles`; called once.
  virtual void build(core::Bvh bvh, const Triangles& triangles) = 0;
  /// Refits the structure to moved triangles (same triangles, same tree: boxes and the
  /// triangle data recomputed). `index_of` maps an internal id to its triangle's place in
  /// `triangles` (null: they are the same). Returns the SAH cost after the refit (AccelInfo::sah_cost's measure).
  virtual double refit(const Triangles& triangles, const std::uint32_t* index_of) = 0;
  /// The SAH cost of the structure as it is.
  virtual double sah_cost() const = 0;
};

/// The wide BVH over triangle blocks with the SIMD kernels of `test` on `isa` (resolved, not
/// scalar); robust = false drops the slab padding.
std::unique_ptr<TriangleEngine> make_wide_engine(TriangleTest test, Isa isa, bool robust);
/// The SIMD engine over a WideAccel that adopted a saved structure (Accel::load).
std::unique_ptr<TriangleEngine> make_wide_engine(std::unique_ptr<WideAccel> adopted);
/// The scalar oracle: the binary BVH and the float triangle test, as core/ defines them.
std::unique_ptr<TriangleEngine> make_oracle_engine(TriangleTest test, bool robust);
/// The accuracy reference (Options::reference_double): the oracle's traversal with robust
/// slabs, the triangle test in double on the widened ray.
std::unique_ptr<TriangleEngine> make_reference_engine(TriangleTest test);
/// Planar polygons by the even-odd crossing rule, over their own binary BVH.
/// It keeps the polygons and their ids.
std::unique_ptr<Engine> make_polygon_engine(std::vector<core::Polygon> polygons, std::vector<std::uint32_t> ids,
                                            bool robust);

/// Lane i of a packet as a ray.
template <int K>
Ray lane_ray(const RayPacket<K>& p, int i) {
  return Ray{{p.ox[i], p.oy[i], p.oz[i]}, p.tmin[i], {p.dx[i], p.dy[i], p.dz[i]}, p.tmax[i]};
}

/// Copies the lanes `lanes` of `p` into a 16-lane packet; every other lane is inert and
/// inactive. The kernels load and store whole chunks of lanes, so a packet with inactive
/// lanes reaches them only as this copy: the caller's inactive lanes are never read (they
/// may be uninitialised) nor written (they may be another thread's).
template <int K>
inline void widen(const RayPacket<K>& p, std::uint32_t lanes, RayPacket<16>& out) {
  for (int i = 0; i < 16; ++i) {
    if (i < K && (lanes >> i & 1u)) {
      out.ox[i] = p.ox[i], out.oy[i] = p.oy[i], out.oz[i] = p.oz[i];
      out.dx[i] = p.dx[i], out.dy[i] = p.dy[i], out.dz[i] = p.dz[i];
      out.tmin[i] = p.tmin[i], out.tmax[i] = p.tmax[i];
    } else {
      out.ox[i] = out.oy[i] = out.oz[i] = out.dx[i] = out.dy[i] = out.dz[i] = out.tmin[i] = 0.0f;
      out.tmax[i] = -INFINITY;
    }
  }
  out.active = lanes;
}

/// The oracle's ray type.
inline core::RayT<float> to_core(const Ray& r) {
  return {{r.org[0], r.org[1], r.org[2]}, r.tmin, {r.dir[0], r.dir[1], r.dir[2]}, r.tmax};
}

}  // namespace volley::accel
