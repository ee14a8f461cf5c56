// The scalar oracle as an engine: core/'s binary BVH traversal and float triangle tests,
// the answers every SIMD kernel is tested against (Isa::scalar).
#include <memory>
#include <vector>

#include "accel/engine.h"
#include "accel/scalar_engine.h"
#include "core/bvh_traverse.h"
#include "core/triangle.h"

namespace volley::accel {
namespace {

class OracleEngine final : public ScalarTriangleEngine<OracleEngine, float> {
 public:
  OracleEngine(TriangleTest test, bool robust) : ScalarTriangleEngine(test, robust) {}

  template <bool AnyHit, bool Robust, bool Excludes>
  bool trace(const core::RayT<float>& r, Hit& hit, std::uint32_t excluded) const {
    if (bvh_.nodes.empty()) return false;
    const core::WoopRay<float> woop = core::make_woop_ray(r.dir);
    return core::traverse<AnyHit, Robust>(bvh_, r, [&](std::uint32_t prim, float& tmax) {
      if constexpr (Excludes) {
        if (triangles_.ids[prim] == excluded) return false;
      }
      core::RayT<float> q = r;
      q.tmax = tmax;
      core::TriHit<float> h;
      if (!test_triangle(q, woop, prim, h)) return false;
      tmax = h.t;
      hit = {h.t, h.u, h.v, triangles_.ids[prim]};
      return true;
    });
  }
};

}  // namespace

std::unique_ptr<TriangleEngine> make_oracle_engine(TriangleTest test, bool robust) {
  return std::make_unique<OracleEngine>(test, robust);
}

}  // namespace volley::accel
