// The scalar oracle as an engine: core/'s binary BVH traversal and float triangle tests,
// the answers every SIMD kernel is tested against (Isa::scalar).
#include <memory>
#include <vector>

#include "accel/engine.h"
#include "core/bvh_traverse.h"
#include "core/triangle.h"

namespace volley::accel {
namespace {

class OracleEngine final : public TriangleEngine {
 public:
  OracleEngine(TriangleTest test, bool robust) : test_(test), robust_(robust) {}

  core::BvhBuildOptions bvh_options() const override { return {}; }
  void build(core::Bvh bvh, const Triangles& t) override {
    bvh_ = std::move(bvh);
    triangles_ = t;
    stats_ = core::bvh_stats(bvh_, core::BvhBuildOptions{});
    if (test_ == TriangleTest::plane) {
      planes_.reserve(t.count);
      for (std::size_t i = 0; i < t.count; ++i) {
        const glm::vec3* p = &t.vertices[3 * i];
        planes_.push_back(core::PlaneTriangle<float>::from(p[0], p[1], p[2]));
      }
    }
  }

  bool intersect(const Ray& ray, Hit& hit) const override {
    core::RayT<float> r = to_core(ray);
    r.tmax = hit.t < r.tmax ? hit.t : r.tmax;
    return robust_ ? trace<false, true>(r, hit) : trace<false, false>(r, hit);
  }
  bool occluded(const Ray& ray) const override {
    Hit unused;
    const core::RayT<float> r = to_core(ray);
    return robust_ ? trace<true, true>(r, unused) : trace<true, false>(r, unused);
  }

  void describe(AccelInfo& info) const override {
    info.nodes = stats_.nodes;
    info.leaves = stats_.leaves;
    info.depth = stats_.depth;
    info.sah_cost = stats_.sah_cost;
    info.mean_leaf_size = stats_.mean_leaf_size;
    info.mean_children = 2.0;
    // The triangle layout of the test in use (the input copy kept for re-commits not counted).
    info.bytes = stats_.bytes + (test_ == TriangleTest::plane ? planes_.size() * sizeof(core::PlaneTriangle<float>)
                                                              : triangles_.count * 3 * sizeof(glm::vec3));
  }

 private:
  template <bool AnyHit, bool Robust>
  bool trace(const core::RayT<float>& r, Hit& hit) const {
    if (bvh_.nodes.empty()) return false;
    const core::WoopRay<float> woop = core::make_woop_ray(r.dir);
    return core::traverse<AnyHit, Robust>(bvh_, r, [&](std::uint32_t prim, float& tmax) {
      const glm::vec3* p = &triangles_.vertices[3 * prim];
      core::RayT<float> q = r;
      q.tmax = tmax;
      core::TriHit<float> h;
      bool ok = false;
      switch (test_) {
        case TriangleTest::plane:
          ok = core::intersect_plane(q, planes_[prim], h);
          break;
        case TriangleTest::moller:
          ok = core::intersect_moller<float, core::moller_fused_for(Isa::scalar)>(q, p[0], p[1], p[2], h);
          break;
        case TriangleTest::watertight:
          ok = core::intersect_watertight(q, woop, p[0], p[1], p[2], h);
          break;
      }
      if (!ok) return false;
      tmax = h.t;
      hit = {h.t, h.u, h.v, triangles_.ids[prim]};
      return true;
    });
  }

  TriangleTest test_;
  bool robust_;
  core::Bvh bvh_;
  core::BvhStats stats_;
  Triangles triangles_{};
  std::vector<core::PlaneTriangle<float>> planes_;  ///< `plane` only
};

}  // namespace

std::unique_ptr<TriangleEngine> make_oracle_engine(TriangleTest test, bool robust) {
  return std::make_unique<OracleEngine>(test, robust);
}

}  // namespace volley::accel
