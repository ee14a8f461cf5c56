// The batch shader: each group of L hits is gathered into lanes, the surface point,
// its error bound, the normal, Phong direct light and the shadow-ray origins are computed
// for all lanes at once, and the results are written back in the scalar loop's order.
// Every expression mirrors Scene::surface_as, queue_direct_lighting and spawn_shadow_ray
// operation for operation (glm's dot is (x + y) + z, normalize is v * (1 / sqrt(dot)));
// only std::pow stays per lane, and what follows direct light (the integrator's
// continuation: ambient and emission, or the path's next bounce) runs lane by lane.
#include "render/shade_batch.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <xsimd/xsimd.hpp>

#include "render/spawn.h"

namespace volley::render {
namespace {

using B = xsimd::batch<float>;
using I = xsimd::batch<std::int32_t>;
constexpr int L = int(B::size);

struct V3 {
  B x, y, z;
};

V3 operator+(const V3& a, const V3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
V3 operator-(const V3& a, const V3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V3 operator*(const B& s, const V3& a) { return {s * a.x, s * a.y, s * a.z}; }
V3 operator*(const V3& a, const B& s) { return {a.x * s, a.y * s, a.z * s}; }
V3 abs(const V3& a) { return {xsimd::abs(a.x), xsimd::abs(a.y), xsimd::abs(a.z)}; }
B dot(const V3& a, const V3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }  // (x + y) + z, as glm
V3 normalize(const V3& a) { return a * (B(1.0f) / xsimd::sqrt(dot(a, a))); }
// std::max(a, b) = a < b ? b : a.
B max_of(const B& a, const B& b) { return xsimd::select(a < b, b, a); }
V3 max_of(const V3& a, const V3& b) { return {max_of(a.x, b.x), max_of(a.y, b.y), max_of(a.z, b.z)}; }

// std::nextafter(x, +inf) (Up) or (x, -inf) for finite x, on the bit patterns.
template <bool Up>
B next_float(const B& x) {
  const I bits = xsimd::bitwise_cast<I>(x);
  const B zero(0.0f);
  const I step = Up ? xsimd::select(xsimd::bool_cast(x < zero), I(-1), I(1))
                    : xsimd::select(xsimd::bool_cast(x > zero), I(-1), I(1));
  const B moved = xsimd::bitwise_cast<B>(bits + step);
  // From +-0 the next float is the smallest subnormal of the direction's sign.
  const B tiny(Up ? std::numeric_limits<float>::denorm_min() : -std::numeric_limits<float>::denorm_min());
  return xsimd::select(x == zero, tiny, moved);
}

// Bit k set when lane k of `m` is true.
std::uint32_t bits_of(const xsimd::batch_bool<float>& m) {
  alignas(64) float f[L];
  xsimd::select(m, B(1.0f), B(0.0f)).store_aligned(f);
  std::uint32_t bits = 0;
  for (int k = 0; k < L; ++k) bits |= (f[k] != 0.0f ? 1u : 0u) << k;
  return bits;
}

// The lanes of a group, loaded from per-lane scalars.
struct Lanes {
  alignas(64) float v[L];
  B load() const { return B::load_aligned(v); }
};
struct Lanes3 {
  Lanes x, y, z;
  void set(int k, const glm::vec3& a) { x.v[k] = a.x, y.v[k] = a.y, z.v[k] = a.z; }
  V3 load() const { return {x.load(), y.load(), z.load()}; }
};
void store(const V3& a, Lanes3& out) {
  a.x.store_aligned(out.x.v);
  a.y.store_aligned(out.y.v);
  a.z.store_aligned(out.z.v);
}
glm::vec3 lane(const Lanes3& a, int k) { return {a.x.v[k], a.y.v[k], a.z.v[k]}; }

// One light's shadow query for every lane of a group.
struct LightLanes {
  std::uint32_t lit = 0;  // lanes that queue a shadow ray
  Lanes r_dot_v;          // for the specular term (std::pow stays per lane)
  Lanes3 diffuse_term, org, dir;
  Lanes dist2;
};

}  // namespace

void shade_batch(const Scene& scene, unsigned stages, ShadeFn one, ContinueFn then, const PathState* paths,
                 const Hit* hits, std::size_t n, int max_depth, std::vector<PathState>& next,
                 std::vector<ShadowQuery>& shadows, glm::vec3* sum) {
  const std::size_t triangles = scene.triangle_count();
  const glm::vec3* pos = scene.positions().data();
  const std::uint32_t* idx = scene.indices().data();
  const std::uint32_t* tri_material = scene.triangle_materials().data();
  const std::vector<io::Material>& materials = scene.materials();
  const bool shadows_on = (stages & kShadows) != 0;
  const std::size_t light_count = shadows_on ? scene.lights().size() : 0;
  // Per thread and reused: this runs once per bounce of every tile.
  thread_local std::vector<LightLanes> per_light;
  per_light.resize(light_count);

  if (triangles == 0) {  // polygons only: nothing to gather
    for (std::size_t i = 0; i < n; ++i) sum[paths[i].pixel] += one(scene, paths[i], hits[i], max_depth, next, shadows);
    return;
  }
  for (std::size_t first = 0; first < n; first += L) {
    const int count = int(std::min<std::size_t>(L, n - first));
    // Gather the lanes that hit a triangle; the others are shaded one at a time below.
    std::uint32_t batch = 0;
    Lanes u, v;
    Lanes3 p0, p1, p2, dir, diffuse;
    std::uint32_t material[L] = {};
    for (int k = 0; k < L; ++k) {
      const bool ok = k < count && hits[first + k].hit() && hits[first + k].prim < triangles;
      const Hit& h = hits[first + (ok ? k : 0)];
      if (ok) batch |= 1u << k;
      const std::uint32_t* t = ok ? idx + 3 * std::size_t(h.prim) : idx;
      // Inert lanes compute on a copy of triangle 0 of the scene seen by a unit ray.
      p0.set(k, pos[t[0]]);
      p1.set(k, pos[t[1]]);
      p2.set(k, pos[t[2]]);
      u.v[k] = ok ? h.u : 0.25f;
      v.v[k] = ok ? h.v : 0.25f;
      const Ray& r = paths[first + (ok ? k : 0)].ray;
      dir.set(k, ok ? glm::vec3(r.dir[0], r.dir[1], r.dir[2]) : glm::vec3(0.0f, 0.0f, 1.0f));
      material[k] = ok ? tri_material[h.prim] : 0;
      diffuse.set(k, materials[material[k]].diffuse);
    }
    Lanes3 point, point_error, normal, view_dir;
    std::uint32_t front_bits = 0;
    if (batch != 0) {
      // render::hit_point and the normal of Scene::surface_as<false>.
      const V3 a = p0.load(), b = p1.load(), c = p2.load();
      const B bu = u.load(), bv = v.load();
      const B b0 = B(1.0f) - bu - bv;
      const V3 p = b0 * a + bu * b + bv * c;
      V3 p_error = B(gamma(7)) * (abs(b0 * a) + abs(bu * b) + abs(bv * c));
      const V3 reach = max_of(abs(a - p), max_of(abs(b - p), abs(c - p)));
      const B reach_max = max_of(reach.x, max_of(reach.y, reach.z));
      p_error = p_error + V3{B(gamma(8)) * reach_max, B(gamma(8)) * reach_max, B(gamma(8)) * reach_max};
      const V3 e1 = b - a, e2 = c - a;
      V3 ng = normalize(V3{e1.y * e2.z - e2.y * e1.z, e1.z * e2.x - e2.z * e1.x, e1.x * e2.y - e2.x * e1.y});
      const V3 d_raw = dir.load();
      const auto front = dot(ng, d_raw) < B(0.0f);
      ng = {xsimd::select(front, ng.x, -ng.x), xsimd::select(front, ng.y, -ng.y), xsimd::select(front, ng.z, -ng.z)};
      // queue_direct_lighting with ns = ng, view_dir = normalize(dir).
      const V3 view = normalize(d_raw);
      store(p, point);
      store(p_error, point_error);
      store(ng, normal);
      store(view, view_dir);
      front_bits = bits_of(front);
      const V3 kd = diffuse.load();
      const V3 abs_p = abs(p);
      const B p_max = max_of(abs_p.x, max_of(abs_p.y, abs_p.z));
      const V3 err = p_error + V3{B(gamma(2)) * p_max, B(gamma(2)) * p_max, B(gamma(2)) * p_max};
      const B err_n = dot(abs(ng), err);
      for (std::size_t j = 0; j < light_count; ++j) {
        const glm::vec3& lp = scene.lights()[j].position;
        const V3 light{B(lp.x), B(lp.y), B(lp.z)};
        const V3 to_light = light - p;
        const B dist2 = dot(to_light, to_light);
        const B len = xsimd::sqrt(dist2);
        const V3 l{to_light.x / len, to_light.y / len, to_light.z / len};
        const B n_dot_l = dot(ng, l);  // = dot(l, ng) = dot(ns, l): products commute
        LightLanes& out = per_light[j];
        // Lit unless n.l <= 0 (a NaN n.l stays lit, as in the scalar test).
        out.lit = ~bits_of(n_dot_l <= B(0.0f)) & batch;
        store(kd * n_dot_l, out.diffuse_term);
        // reflect(-l, ns) = d - 2 dot(d, n) n with d = -l; then its dot with -view.
        const V3 ml{-l.x, -l.y, -l.z};
        const B two_dot = B(2.0f) * dot(ml, ng);
        const V3 r = ml - two_dot * ng;
        dot(r, V3{-view.x, -view.y, -view.z}).store_aligned(out.r_dot_v.v);
        dist2.store_aligned(out.dist2.v);
        // spawn_shadow_ray(p, p_error, ng, light): offset_origin toward light - p.
        const auto toward = dot(to_light, ng) < B(0.0f);
        const B side = xsimd::select(toward, B(-1.0f), B(1.0f));
        const V3 offset = (side * err_n) * ng;
        const V3 moved = p + offset;
        const B zero(0.0f);
        auto round_away = [&](const B& po, const B& off) {
          return xsimd::select(off > zero, next_float<true>(po), xsimd::select(off < zero, next_float<false>(po), po));
        };
        const V3 o{round_away(moved.x, offset.x), round_away(moved.y, offset.y), round_away(moved.z, offset.z)};
        store(o, out.org);
        store(light - o, out.dir);
      }
    }
    // Write back in the one-at-a-time order: per path, its direct light, then its queries.
    for (int k = 0; k < count; ++k) {
      const std::size_t i = first + k;
      const PathState& path = paths[i];
      if (!((batch >> k) & 1u)) {
        sum[path.pixel] += one(scene, path, hits[i], max_depth, next, shadows);
        continue;
      }
      const io::Material& m = materials[material[k]];
      const bool specular = m.specular != glm::vec3(0.0f);
      if (m.diffuse != glm::vec3(0.0f) || specular) {
        for (std::size_t j = 0; j < light_count; ++j) {
          const LightLanes& ll = per_light[j];
          if (!((ll.lit >> k) & 1u)) continue;
          glm::vec3 c = lane(ll.diffuse_term, k);
          const float r_dot_v = ll.r_dot_v.v[k];
          if (specular && r_dot_v > 0.0f) c += m.specular * std::pow(r_dot_v, m.shininess);
          const io::PointLight& light = scene.lights()[j];
          const glm::vec3 o = lane(ll.org, k), d = lane(ll.dir, k);
          shadows.push_back({Ray{{o.x, o.y, o.z}, 0.0f, {d.x, d.y, d.z}, 1.0f},
                             path.weight * c * light.intensity / ll.dist2.v[k], path.pixel});
        }
      }
      SurfacePoint sp;
      sp.p = lane(point, k);
      sp.p_error = lane(point_error, k);
      sp.ng = sp.ns = lane(normal, k);
      sp.front = (front_bits >> k) & 1u;
      sp.material = material[k];
      sum[path.pixel] += then(scene, path, sp, lane(view_dir, k), max_depth, next);
    }
  }
}

}  // namespace volley::render
