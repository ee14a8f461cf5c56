// Accel::geometric_normal: the normal of the primitive a hit names, from the geometry as
// added (also while a loaded Accel's input is still in its file), through instances.
#include <cmath>
#include <limits>

#include "accel/accel_impl.h"
#include "accel/parallel.h"

namespace volley {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

/// v / |v|, NaN for a zero or non-finite length.
std::array<float, 3> unit(const double v[3]) {
  const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (!(len > 0.0) || !std::isfinite(len)) return {kNaN, kNaN, kNaN};
  return {static_cast<float>(v[0] / len), static_cast<float>(v[1] / len), static_cast<float>(v[2] / len)};
}

/// unit((p1 - p0) x (p2 - p0)) in double: for triangles whose float cross product over- or
/// underflows.
[[gnu::noinline, gnu::cold]] std::array<float, 3> triangle_normal_double(const float* p0, const float* p1, const float* p2) {
  const double f1[3] = {double(p1[0]) - p0[0], double(p1[1]) - p0[1], double(p1[2]) - p0[2]};
  const double f2[3] = {double(p2[0]) - p0[0], double(p2[1]) - p0[1], double(p2[2]) - p0[2]};
  const double m[3] = {f1[1] * f2[2] - f1[2] * f2[1], f1[2] * f2[0] - f1[0] * f2[2], f1[0] * f2[1] - f1[1] * f2[0]};
  return unit(m);
}

/// unit((p1 - p0) x (p2 - p0)): in float (a normal per hit is asked for batches of
/// millions), in double where float over- or underflows.
inline std::array<float, 3> triangle_normal(const float* p0, const float* p1, const float* p2) {
  const float e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
  const float e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
  const float n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
  const float len2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
  if (!(len2 > 0x1p-100f && len2 < 0x1p100f)) [[unlikely]]
    return triangle_normal_double(p0, p1, p2);
  const float s = 1.0f / std::sqrt(len2);
  return {n[0] * s, n[1] * s, n[2] * s};
}

}  // namespace

std::array<float, 3> Accel::Impl::local_normal(std::uint32_t geom, std::uint32_t prim) const {
  if (geom >= added.geometries.size()) return {kNaN, kNaN, kNaN};
  const Geometry& g = added.geometries[geom];
  if (g.kind == Kind::instance || prim >= g.count) return {kNaN, kNaN, kNaN};
  if (g.kind == Kind::polygon) {
    const core::Polygon& p = added.polygons[g.index];
    const double n[3] = {p.normal.x, p.normal.y, p.normal.z};
    return unit(n);
  }
  // The three vertices: from the copies (built, or unpacked), or from the mapped file.
  const float* v[3];
  for (int k = 0; k < 3; ++k) {
    if (mapped.packed) {
      const std::uint32_t index = mapped.packed->indices[3 * (g.index + prim) + static_cast<std::size_t>(k)];
      v[k] = &mapped.packed->vertices[3 * (g.packed_vertices + index)];
    } else {
      v[k] = &added.triangles[3 * (g.index + prim) + static_cast<std::size_t>(k)].x;
    }
  }
  return triangle_normal(v[0], v[1], v[2]);
}

std::array<float, 3> Accel::geometric_normal(const Hit& hit) const {
  if (!impl_->built.committed) throw Error("geometric_normal: call commit() after adding geometry");
  if (!hit.hit()) return {kNaN, kNaN, kNaN};
  if (hit.inst == kInvalidId) return impl_->local_normal(hit.geom, hit.prim);
  if (hit.inst >= impl_->added.geometries.size() || impl_->added.geometries[hit.inst].kind != Impl::Kind::instance)
    return {kNaN, kNaN, kNaN};
  const Impl::Instance& in = impl_->added.instances[impl_->added.geometries[hit.inst].index];
  const std::array<float, 3> n = in.prototype->local_normal(hit.geom, hit.prim);
  // Normals map by the inverse transpose: world n = A^-T n_object, A^-1 being to_object's 3x3.
  const float* m = in.to_object;
  double w[3];
  for (int c = 0; c < 3; ++c) w[c] = double(m[c]) * n[0] + double(m[4 + c]) * n[1] + double(m[8 + c]) * n[2];
  return unit(w);
}

void Accel::geometric_normals(const Hit* hits, std::size_t count, float* xyz, int threads) const {
  if (!impl_->built.committed) throw Error("geometric_normals: call commit() after adding geometry");
  if (count > 0 && (!hits || !xyz)) throw Error("geometric_normals: hits or xyz is null with count > 0");
  const Impl& im = *impl_;
  auto normals = [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Hit& h = hits[i];
      std::array<float, 3> n{kNaN, kNaN, kNaN};
      if (!h.hit()) {
        // a miss (most rays of many batches): no call
      } else if (const Impl::Geometry* g =
                     h.inst == kInvalidId && !im.mapped.packed && h.geom < im.added.geometries.size()
                         ? &im.added.geometries[h.geom]
                         : nullptr;
                 g && g->kind == Impl::Kind::triangles && h.prim < g->count) {
        // A triangle of this Accel as added (most hits): local_normal without its call.
        const glm::vec3* p = &im.added.triangles[3 * (g->index + h.prim)];
        n = triangle_normal(&p[0].x, &p[1].x, &p[2].x);
      } else {
        n = geometric_normal(h);
      }
      xyz[3 * i] = n[0], xyz[3 * i + 1] = n[1], xyz[3 * i + 2] = n[2];
    }
  };
  accel::for_chunks("geometric_normals", count, threads, normals, 4096);
}

}  // namespace volley
