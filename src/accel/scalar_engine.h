// What the scalar engines (oracle_engine.cpp, reference_engine.cpp, polygon_engine.cpp)
// share: single-ray queries on core/'s binary BVH walk with the committed slab test, and
// for triangles the BVH and plane data they keep.
#pragma once
#include <cmath>
#include <cstddef>
#include <utility>
#include <vector>

#include "accel/engine.h"
#include "core/bvh.h"
#include "core/bvh_nearest.h"
#include "core/bvh_traverse.h"
#include "core/triangle.h"

namespace volley::accel {

/// The single-ray queries of an engine whose Derived::trace<AnyHit, Robust, Excludes>(ray,
/// hit, excluded) walks core/'s binary BVH (Robust: padded slabs, Options::robust;
/// Excludes: the primitive of id `excluded` is passed over). Packets go lane by lane
/// (Engine's default).
template <class Derived, class Base>
class ScalarQueries : public Base {
 public:
  explicit ScalarQueries(bool robust) : robust_(robust) {}

  bool intersect(const Ray& ray, Hit& hit) const override {
    core::RayT<float> r = to_core(ray);
    r.tmax = hit.t < r.tmax ? hit.t : r.tmax;
    return robust_ ? self().template trace<false, true, false>(r, hit, kInvalidPrim)
                   : self().template trace<false, false, false>(r, hit, kInvalidPrim);
  }
  bool occluded(const Ray& ray) const override {
    Hit unused;
    const core::RayT<float> r = to_core(ray);
    return robust_ ? self().template trace<true, true, false>(r, unused, kInvalidPrim)
                   : self().template trace<true, false, false>(r, unused, kInvalidPrim);
  }
  bool intersect_excluding(const Ray& ray, std::uint32_t excluded, Hit& hit) const override {
    return closest<true>(ray, excluded, hit);
  }
  bool occluded_excluding(const Ray& ray, std::uint32_t excluded) const override { return any<true>(ray, excluded); }

 private:
  const Derived& self() const { return static_cast<const Derived&>(*this); }
  template <bool Excludes>
  bool closest(const Ray& ray, std::uint32_t excluded, Hit& hit) const {
    core::RayT<float> r = to_core(ray);
    r.tmax = hit.t < r.tmax ? hit.t : r.tmax;
    return robust_ ? self().template trace<false, true, Excludes>(r, hit, excluded)
                   : self().template trace<false, false, Excludes>(r, hit, excluded);
  }
  template <bool Excludes>
  bool any(const Ray& ray, std::uint32_t excluded) const {
    Hit unused;
    const core::RayT<float> r = to_core(ray);
    return robust_ ? self().template trace<true, true, Excludes>(r, unused, excluded)
                   : self().template trace<true, false, Excludes>(r, unused, excluded);
  }

 protected:
  /// Calls leaf(prim) for the primitives of every leaf the ray's box test passes (the
  /// committed slab test; nothing pruned): the walk of the crossing queries.
  template <class Leaf>
  void every_leaf(const core::Bvh& bvh, const Ray& ray, Leaf&& leaf) const {
    auto each = [&](std::uint32_t prim, float&) {
      leaf(prim);
      return false;
    };
    const core::RayT<float> r = to_core(ray);
    robust_ ? core::traverse<false, true>(bvh, r, each) : core::traverse<false, false>(bvh, r, each);
  }
  bool robust_;
};

/// A scalar triangle engine in Real precision (the oracle in float, the reference in
/// double): the binary BVH over the triangles as built, and for the plane test each
/// triangle's planes. Derived provides trace().
template <class Derived, class Real>
class ScalarTriangleEngine : public ScalarQueries<Derived, TriangleEngine> {
 public:
  ScalarTriangleEngine(TriangleTest test, bool robust) : ScalarQueries<Derived, TriangleEngine>(robust), test_(test) {}

  core::BvhBuildOptions bvh_options() const override { return {}; }
  void build(core::Bvh bvh, const Triangles& t) override {
    bvh_ = std::move(bvh);
    triangles_ = t;
    stats_ = core::bvh_stats(bvh_, core::BvhBuildOptions{});
    if (test_ != TriangleTest::plane) return;
    planes_.reserve(t.count);
    for (std::size_t i = 0; i < t.count; ++i) planes_.push_back(plane_of(i));
  }
  double refit(const Triangles& t, const std::uint32_t*) override {
    triangles_ = t;
    if (!bvh_.nodes.empty()) refit_node(0);
    stats_ = core::bvh_stats(bvh_, core::BvhBuildOptions{});
    if (test_ == TriangleTest::plane)
      for (std::size_t i = 0; i < t.count; ++i) planes_[i] = plane_of(i);
    return stats_.sah_cost;
  }
  double sah_cost() const override { return stats_.sah_cost; }

  /// The crossing queries: every triangle hit, by the crossing rule for the watertight test
  /// (in Real, t, u, v rounded to float; a t that rounds onto tmax is dropped).
  void all_hits(const Ray& ray, std::vector<Hit>& out) const override {
    if (bvh_.nodes.empty()) return;
    const core::RayT<Real> q = core::ray_cast<Real>(to_core(ray));
    const core::WoopRay<Real> woop = core::make_woop_ray(q.dir);
    this->every_leaf(bvh_, ray, [&](std::uint32_t prim) {
      core::TriHit<Real> h;
      const bool hit = test_ == TriangleTest::watertight ? crossing_triangle(q, woop, prim, h) : test_triangle(q, woop, prim, h);
      if (hit && float(h.t) < ray.tmax) out.push_back(Hit{float(h.t), float(h.u), float(h.v), triangles_.ids[prim]});
    });
  }
  /// The nearest triangle point (in Real, as core::offer_triangle_vertices); left-out
  /// triangles (degenerate, another layer's, disabled) are skipped as the wide blocks skip them.
  void closest_point(core::PointQuery& query) const override {
    core::nearest_walk(bvh_, query, [&](std::uint32_t prim) {
      if (triangles_.excluded[prim]) return;
      const glm::vec3* p = &triangles_.vertices[3 * std::size_t{prim}];
      const Real a[3] = {p[0].x, p[0].y, p[0].z}, b[3] = {p[1].x, p[1].y, p[1].z}, c[3] = {p[2].x, p[2].y, p[2].z};
      core::offer_triangle_vertices(query, a, b, c, triangles_.ids[prim]);
    });
  }

  void describe(AccelInfo& info) const override {
    info.nodes = stats_.nodes;
    info.leaves = stats_.leaves;
    info.depth = stats_.depth;
    info.sah_cost = stats_.sah_cost;
    info.mean_leaf_size = stats_.mean_leaf_size;
    info.mean_children = 2.0;
    info.references = static_cast<std::size_t>(std::llround(stats_.mean_leaf_size * double(stats_.leaves)));
    // The triangle layout of the test in use (the input copy kept for re-commits not counted).
    info.bytes = stats_.bytes + (test_ == TriangleTest::plane ? planes_.size() * sizeof(core::PlaneTriangle<Real>)
                                                              : triangles_.count * 3 * sizeof(glm::vec3));
  }

 protected:
  core::PlaneTriangle<Real> plane_of(std::size_t i) const {
    const glm::vec3* p = &triangles_.vertices[3 * i];
    return core::PlaneTriangle<Real>::from(core::Vec3<Real>(p[0]), core::Vec3<Real>(p[1]), core::Vec3<Real>(p[2]));
  }
  /// The box of node n's subtree from the triangles as they are now; a triangle left out
  /// at the build (Triangles::excluded) keeps its empty box. Depth <= kBvhMaxDepth.
  core::BBox refit_node(std::uint32_t n) {
    core::BvhNode& node = bvh_.nodes[n];
    core::BBox box;
    if (node.is_leaf()) {
      for (std::uint32_t k = 0; k < node.count; ++k) {
        const std::uint32_t prim = bvh_.prim_index[node.first_or_child + k];
        if (triangles_.excluded[prim]) continue;
        for (int c = 0; c < 3; ++c) box.extend(triangles_.vertices[3 * std::size_t{prim} + c]);
      }
    } else {
      box = refit_node(node.first_or_child);
      box.extend(refit_node(node.first_or_child + 1));
    }
    node.box = box;
    return box;
  }

  /// Triangle `prim` against `q` by the committed test (`woop`: q's shear).
  bool test_triangle(const core::RayT<Real>& q, const core::WoopRay<Real>& woop, std::uint32_t prim,
                     core::TriHit<Real>& h) const {
    const glm::vec3* p = &triangles_.vertices[3 * prim];
    const core::Vec3<Real> p0(p[0]), p1(p[1]), p2(p[2]);
    switch (test_) {
      case TriangleTest::plane:
        return core::intersect_plane(q, planes_[prim], h);
      case TriangleTest::moller:
        return core::intersect_moller<Real, core::moller_fused_for(Isa::scalar)>(q, p0, p1, p2, h);
      case TriangleTest::watertight:
        return core::intersect_watertight(q, woop, p0, p1, p2, h);
    }
    return false;
  }

  /// The watertight test with the crossing rule (core::intersect_watertight's Crossing).
  bool crossing_triangle(const core::RayT<Real>& q, const core::WoopRay<Real>& woop, std::uint32_t prim,
                         core::TriHit<Real>& h) const {
    const glm::vec3* p = &triangles_.vertices[3 * prim];
    return core::intersect_watertight<Real, false, true>(q, woop, core::Vec3<Real>(p[0]), core::Vec3<Real>(p[1]),
                                                         core::Vec3<Real>(p[2]), h);
  }

  TriangleTest test_;
  core::Bvh bvh_;
  core::BvhStats stats_;
  Triangles triangles_{};
  std::vector<core::PlaneTriangle<Real>> planes_;  ///< `plane` only
};

}  // namespace volley::accel
