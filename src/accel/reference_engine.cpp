// The accuracy reference as an engine (Options::reference_double): the oracle's binary
// BVH walked with robust slabs, each triangle tested in double on the widened ray and
// t, u, v rounded to float. `volley accuracy` measures every configuration against it
// (docs/accuracy.md).
#include <memory>
#include <vector>

#include "accel/engine.h"
#include "core/bvh_traverse.h"
#include "core/triangle.h"

namespace volley::accel {
namespace {

class ReferenceEngine final : public TriangleEngine {
 public:
  explicit ReferenceEngine(TriangleTest test) : test_(test) {}

  core::BvhBuildOptions bvh_options() const override { return {}; }
  void build(core::Bvh bvh, const Triangles& t) override {
    bvh_ = std::move(bvh);
    triangles_ = t;
    stats_ = core::bvh_stats(bvh_, core::BvhBuildOptions{});
    if (test_ == TriangleTest::plane) {
      // The planes of the widened vertices.
      planes_.reserve(t.count);
      for (std::size_t i = 0; i < t.count; ++i) {
        const glm::vec3* p = &t.vertices[3 * i];
        planes_.push_back(core::PlaneTriangle<double>::from(core::Vec3<double>(p[0]), core::Vec3<double>(p[1]),
                                                            core::Vec3<double>(p[2])));
      }
    }
  }

  bool intersect(const Ray& ray, Hit& hit) const override {
    core::RayT<float> r = to_core(ray);
    r.tmax = hit.t < r.tmax ? hit.t : r.tmax;
    return trace<false>(r, hit);
  }
  bool occluded(const Ray& ray) const override {
    Hit unused;
    return trace<true>(to_core(ray), unused);
  }

  void describe(AccelInfo& info) const override {
    info.nodes = stats_.nodes;
    info.leaves = stats_.leaves;
    info.depth = stats_.depth;
    info.sah_cost = stats_.sah_cost;
    info.mean_leaf_size = stats_.mean_leaf_size;
    info.mean_children = 2.0;
    info.bytes = stats_.bytes + (test_ == TriangleTest::plane ? planes_.size() * sizeof(core::PlaneTriangle<double>)
                                                              : triangles_.count * 3 * sizeof(glm::vec3));
  }

 private:
  template <bool AnyHit>
  bool trace(const core::RayT<float>& r, Hit& hit) const {
    if (bvh_.nodes.empty()) return false;
    // The widened ray; q.tmax is the nearest double t so far, so triangles closer together
    // than a float ulp are still ordered by their double distances.
    core::RayT<double> q = core::ray_cast<double>(r);
    const core::WoopRay<double> woop = core::make_woop_ray(q.dir);
    // Robust slabs: the float traversal's tmax is the rounded t, within the padding's margin.
    return core::traverse<AnyHit, true>(bvh_, r, [&](std::uint32_t prim, float& tmax) {
      const glm::vec3* p = &triangles_.vertices[3 * prim];
      const core::Vec3<double> p0(p[0]), p1(p[1]), p2(p[2]);
      core::TriHit<double> h;
      bool ok = false;
      switch (test_) {
        case TriangleTest::plane:
          ok = core::intersect_plane(q, planes_[prim], h);
          break;
        case TriangleTest::moller:
          ok = core::intersect_moller(q, p0, p1, p2, h);
          break;
        case TriangleTest::watertight:
          ok = core::intersect_watertight(q, woop, p0, p1, p2, h);
          break;
      }
      // A double t just below tmax can round onto it: [tmin, tmax) holds for the float t.
      const float t = static_cast<float>(h.t);
      if (!ok || !(t < r.tmax)) return false;
      q.tmax = h.t;
      tmax = t;
      hit = {t, static_cast<float>(h.u), static_cast<float>(h.v), triangles_.ids[prim]};
      return true;
    });
  }

  TriangleTest test_;
  core::Bvh bvh_;
  core::BvhStats stats_;
  Triangles triangles_{};
  std::vector<core::PlaneTriangle<double>> planes_;  ///< `plane` only
};

}  // namespace

std::unique_ptr<TriangleEngine> make_reference_engine(TriangleTest test) {
  return std::make_unique<ReferenceEngine>(test);
}

}  // namespace volley::accel
