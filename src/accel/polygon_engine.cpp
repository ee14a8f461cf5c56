// Planar polygons as an engine: the even-odd crossing test (core/polygon.h) over their
// own binary BVH, scalar (scenes hold few polygons).
#include <memory>
#include <vector>

#include "accel/engine.h"
#include "accel/scalar_engine.h"
#include "core/bvh_traverse.h"

namespace volley::accel {
namespace {

class PolygonEngine final : public ScalarQueries<PolygonEngine, Engine> {
 public:
  PolygonEngine(std::vector<core::Polygon> polygons, std::vector<std::uint32_t> ids, bool robust)
      : ScalarQueries(robust), polygons_(std::move(polygons)), ids_(std::move(ids)) {
    std::vector<core::BBox> boxes;
    boxes.reserve(polygons_.size());
    for (const auto& poly : polygons_) {
      core::BBox b;
      for (const auto& v : poly.vertices) b.extend(v);
      boxes.push_back(b);
    }
    bvh_ = core::build_bvh(boxes, core::BvhBuildOptions{});
  }

  void describe(AccelInfo& info) const override {
    const core::BvhStats s = core::bvh_stats(bvh_);
    info.nodes += s.nodes;
    info.leaves += s.leaves;
    info.depth = std::max(info.depth, s.depth);
    info.bytes += s.bytes;
  }

  void all_hits(const Ray& ray, std::vector<Hit>& out) const override {
    if (bvh_.nodes.empty()) return;
    const core::RayT<float> r = to_core(ray);
    every_leaf(bvh_, ray, [&](std::uint32_t prim) {
      float t;
      if (core::intersect_polygon(r, polygons_[prim], t)) out.push_back(Hit{t, 0.0f, 0.0f, ids_[prim]});
    });
  }
  void closest_point(core::PointQuery& query) const override {
    core::nearest_walk(bvh_, query, [&](std::uint32_t prim) { core::offer_polygon(query, polygons_[prim], ids_[prim]); });
  }

  template <bool AnyHit, bool Robust, bool Excludes>
  bool trace(const core::RayT<float>& r, Hit& hit, std::uint32_t excluded) const {
    return core::traverse<AnyHit, Robust>(bvh_, r, [&](std::uint32_t prim, float& tmax) {
      if constexpr (Excludes) {
        if (ids_[prim] == excluded) return false;
      }
      core::RayT<float> q = r;
      q.tmax = tmax;
      float t;
      if (!core::intersect_polygon(q, polygons_[prim], t)) return false;
      tmax = t;
      hit = {t, 0.0f, 0.0f, ids_[prim]};
      return true;
    });
  }

 private:
  std::vector<core::Polygon> polygons_;  // copies of the layer's (a layer may move)
  std::vector<std::uint32_t> ids_;
  core::Bvh bvh_;
};

}  // namespace

std::unique_ptr<Engine> make_polygon_engine(std::vector<core::Polygon> polygons, std::vector<std::uint32_t> ids,
                                            bool robust) {
  return std::make_unique<PolygonEngine>(std::move(polygons), std::move(ids), robust);
}

}  // namespace volley::accel
