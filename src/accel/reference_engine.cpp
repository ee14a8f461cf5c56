// The accuracy reference as an engine (Options::reference_double): the oracle's binary
// BVH walked with robust slabs, each triangle tested in double on the widened ray and
// t, u, v rounded to float. `volley accuracy` measures every configuration against it
// (docs/accuracy.md).
#include <memory>
#include <vector>

#include "accel/engine.h"
#include "accel/scalar_engine.h"
#include "core/bvh_traverse.h"
#include "core/triangle.h"

namespace volley::accel {
namespace {

class ReferenceEngine final : public ScalarTriangleEngine<ReferenceEngine, double> {
 public:
  // Robust slabs always: the float traversal's tmax is the rounded t, within the padding's margin.
  explicit ReferenceEngine(TriangleTest test) : ScalarTriangleEngine(test, true) {}

  /// (Robust is always true: the constructor sets it.)
  template <bool AnyHit, bool Robust, bool Excludes>
  bool trace(const core::RayT<float>& r, Hit& hit, std::uint32_t excluded) const {
    if (bvh_.nodes.empty()) return false;
    // The widened ray; q.tmax is the nearest double t so far, so triangles closer together
    // than a float ulp are still ordered by their double distances.
    core::RayT<double> q = core::ray_cast<double>(r);
    const core::WoopRay<double> woop = core::make_woop_ray(q.dir);
    return core::traverse<AnyHit, Robust>(bvh_, r, [&](std::uint32_t prim, float& tmax) {
      if constexpr (Excludes) {
        if (triangles_.ids[prim] == excluded) return false;
      }
      core::TriHit<double> h;
      if (!test_triangle(q, woop, prim, h)) return false;
      // A double t just below tmax can round onto it: [tmin, tmax) holds for the float t.
      const float t = static_cast<float>(h.t);
      if (!(t < r.tmax)) return false;
      q.tmax = h.t;
      tmax = t;
      hit = {t, static_cast<float>(h.u), static_cast<float>(h.v), triangles_.ids[prim]};
      return true;
    });
  }
};

}  // namespace

std::unique_ptr<TriangleEngine> make_reference_engine(TriangleTest test) {
  return std::make_unique<ReferenceEngine>(test);
}

}  // namespace volley::accel
