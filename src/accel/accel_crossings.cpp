// The crossing queries (docs/crossings.md): every hit along a ray, their count, and
// inside/outside by the parity of one ray's crossings. The engines' walks find the hits
// (the watertight test with its exactly-once rule); here they are gathered over the
// layers and instances, attributed and put in t order.
#include <algorithm>
#include <cmath>

#include "accel/accel_impl.h"
#include "accel/parallel.h"

namespace volley {
namespace {

/// The hits of one ray, in a buffer each thread keeps (no allocation per ray).
std::vector<Hit>& scratch() {
  thread_local std::vector<Hit> kept;
  std::vector<Hit>& hits = *accel::thread_buffer(&kept);
  hits.clear();
  return hits;
}

}  // namespace

void sort_hits(Hit* first, Hit* last) {
  std::sort(first, last, [](const Hit& a, const Hit& b) {
    if (a.t != b.t) return a.t < b.t;
    if (a.inst != b.inst) return a.inst < b.inst;
    if (a.geom != b.geom) return a.geom < b.geom;
    return a.prim < b.prim;
  });
}

void drop_repeated_hits(std::vector<Hit>& hits, std::size_t first) {
  if (hits.size() - first < 2) return;
  const auto begin = hits.begin() + static_cast<std::ptrdiff_t>(first);
  std::sort(begin, hits.end(), [](const Hit& a, const Hit& b) { return a.prim < b.prim; });
  hits.erase(std::unique(begin, hits.end(), [](const Hit& a, const Hit& b) { return a.prim == b.prim; }), hits.end());
}

void Accel::Impl::all_hits(const Ray& ray, std::uint32_t mask, std::vector<Hit>& out) const {
  for (const Layer& l : built.layers) {
    if (!(l.mask & mask)) continue;
    for (const auto& engine : l.engines) {
      const std::size_t first = out.size();
      engine->all_hits(ray, out);
      if (built.quality == BuildQuality::high) drop_repeated_hits(out, first);
      for (std::size_t i = first; i < out.size(); ++i) attribute(out[i].prim, out[i].geom);
    }
  }
  if (built.has_instances) all_hits_instances(ray, mask, out);
}

std::size_t Accel::intersect_all(const Ray& ray, Hit* hits, std::size_t capacity, std::uint32_t mask) const {
  if (!impl_->built.committed) throw Error("intersect_all: call commit() after adding geometry");
  if (!hits && capacity > 0) throw Error("intersect_all: hits is null with capacity > 0");
  std::vector<Hit>& all = scratch();
  impl_->all_hits(ray, mask, all);
  sort_hits(all.data(), all.data() + all.size());
  std::copy_n(all.begin(), std::min(capacity, all.size()), hits);
  return all.size();
}

std::uint32_t Accel::count_intersections(const Ray& ray, std::uint32_t mask) const {
  if (!impl_->built.committed) throw Error("count_intersections: call commit() after adding geometry");
  std::vector<Hit>& all = scratch();
  impl_->all_hits(ray, mask, all);
  return static_cast<std::uint32_t>(all.size());
}

bool Accel::contains(const float point[3]) const {
  if (!impl_->built.committed) throw Error("contains: call commit() after adding geometry");
  if (!point) throw Error("contains: point is null");
  std::vector<Hit>& all = scratch();
  impl_->all_hits(contains_ray(point), kMaskAll, all);
  return all.size() % 2 == 1;
}

}  // namespace volley
