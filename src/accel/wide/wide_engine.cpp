// The SIMD engine: the wide BVH over triangle blocks (WideAccel) and its kernels.
#include <memory>
#include <utility>

#include "accel/engine.h"
#include "accel/wide/wide_accel.h"

namespace volley::accel {
namespace {

static_assert(sizeof(glm::vec3) == 3 * sizeof(float), "triangles are read as packed xyz floats");

/// Binary-BVH options for the wide BVH with leaf blocks of W triangles. The SAH keeps up
/// to 16 triangles in a leaf when splitting does not pay, pricing a triangle test at
/// `intersection_cost` node visits: a block tests W triangles at about the cost of one node
/// visit for a single ray, but packets test every triangle of a leaf against all their
/// lanes, so the best cost lies above 1/W. For W >= 8 an empty block slot is priced too, so
/// that leaves fill their blocks. The values and their measurements: perf/reports/build.md.
core::BvhBuildOptions wide_build_options(int w) {
  core::BvhBuildOptions o;
  o.max_leaf_size = 16;
  o.intersection_cost = w >= 16 ? 0.15f : 0.25f;
  if (w >= 8) {
    o.leaf_block_width = w;
    o.padding_cost = 0.4f;
  }
  return o;
}

class WideEngine final : public TriangleEngine {
 public:
  WideEngine(TriangleTest test, Isa isa, bool robust) : accel_(WideAccel::create(test, isa, robust)) {}
  explicit WideEngine(std::unique_ptr<WideAccel> accel) : accel_(std::move(accel)) {}

  core::BvhBuildOptions bvh_options() const override { return wide_build_options(accel_->block_width()); }
  void build(core::Bvh bvh, const Triangles& t) override {
    accel_->build(bvh, reinterpret_cast<const float*>(t.vertices), t.ids);
  }
  const WideAccel* wide() const override { return accel_.get(); }
  double refit(const Triangles& t, const std::uint32_t* index_of) override {
    accel_->refit(reinterpret_cast<const float*>(t.vertices), index_of);
    return sah_cost();
  }
  double sah_cost() const override { return accel_->stats().sah_cost; }

  bool intersect(const Ray& ray, Hit& hit) const override {
    const float before = hit.t;
    accel_->intersect(ray, hit);
    return hit.t != before;  // the kernels write only a nearer hit
  }
  bool occluded(const Ray& ray) const override { return accel_->occluded(ray); }
  bool intersect_excluding(const Ray& ray, std::uint32_t excluded, Hit& hit) const override {
    const float before = hit.t;
    accel_->intersect(ray, excluded, hit);
    return hit.t != before;
  }
  bool occluded_excluding(const Ray& ray, std::uint32_t excluded) const override {
    return accel_->occluded(ray, excluded);
  }
  void all_hits(const Ray& ray, std::vector<Hit>& out) const override { accel_->all_hits(ray, out); }
  void all_hits(const RayPacket<16>& rays, std::vector<Hit>* out) const override { accel_->all_hits(rays, out); }
  void closest_point(core::PointQuery& query) const override { accel_->closest_point(query); }
  void intersect(const RayPacket<16>& rays, HitPacket<16>& hits) const override { accel_->intersect(rays, hits); }
  std::uint32_t occluded(const RayPacket<16>& rays, std::uint32_t lanes) const override {
    if (lanes == rays.active) return accel_->occluded(rays);
    RayPacket<16> some = rays;  // (Accel::Impl asks for all its active lanes)
    some.active = lanes & rays.active;
    return accel_->occluded(some);
  }
  bool traces_packets() const override { return true; }

  void describe(AccelInfo& info) const override {
    const simd::WideStats& w = accel_->stats();
    info.width = simd::kWideN;
    info.block_width = accel_->block_width();
    info.nodes = w.nodes;
    info.leaves = w.leaves;
    info.depth = w.depth;
    info.sah_cost = w.sah_cost;
    info.mean_leaf_size = w.leaves ? double(w.triangles) / double(w.leaves) : 0.0;
    info.bytes = w.bytes;
    info.blocks = w.blocks;
    info.references = w.triangles;
    info.mean_children = w.mean_children;
    info.block_fill = w.blocks ? double(w.triangles) / double(w.blocks * std::size_t(info.block_width)) : 0.0;
  }

 private:
  std::unique_ptr<WideAccel> accel_;
};

}  // namespace

std::unique_ptr<TriangleEngine> make_wide_engine(std::unique_ptr<WideAccel> adopted) {
  return std::make_unique<WideEngine>(std::move(adopted));
}

std::unique_ptr<TriangleEngine> make_wide_engine(TriangleTest test, Isa isa, bool robust) {
  return std::make_unique<WideEngine>(test, isa, robust);
}

}  // namespace volley::accel
