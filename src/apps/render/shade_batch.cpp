// The batch shader: the triangle hits of a stream are gathered into the rows of a
// structure-of-arrays buffer, the lanes kernel of the chosen ISA computes surface points
// and each light's shadow rays for all of them (shade_lanes.h), and the results are written
// back in the scalar loop's order. Only std::pow stays per hit, and what follows direct
// light (the integrator's continuation: ambient and emission, or the path's next bounce).
#include "render/shade_batch.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "render/shade_lanes.h"
#include "simd/isa/arch.h"

namespace volley::render {
namespace {

struct LaneKernels {
  void (*surfaces)(float* rows, std::size_t stride, std::size_t count);
  void (*light)(const float* rows, std::size_t stride, std::size_t count, const float position[3], float* out);
  std::size_t lanes;
};

template <class Arch>
LaneKernels kernels_of(std::size_t lanes) {
  return {&ShadeLanes<Arch>::surfaces, &ShadeLanes<Arch>::light, lanes};
}

LaneKernels kernels_for(Isa isa) {
  // The scalar oracle shades on SSE4.2 lanes: the build's baseline ISA.
  const Isa lanes_isa = isa == Isa::avx512 || isa == Isa::avx2 ? isa : Isa::sse42;
  return simd::visit_arch(lanes_isa, []<class Arch>(Arch) { return kernels_of<Arch>(simd::kLanes<Arch>); });
}

constexpr std::size_t kRowAlign = 16;  // floats: 64 bytes, the widest lane count
constexpr std::uint32_t kNotInLanes = ~0u;

// `floats` floats starting at a 64-byte boundary inside `buffer`.
float* aligned_floats(std::vector<float>& buffer, std::size_t floats) {
  buffer.resize(floats + kRowAlign);
  const std::size_t misalign = reinterpret_cast<std::uintptr_t>(buffer.data()) % (kRowAlign * sizeof(float));
  return buffer.data() + (misalign ? (kRowAlign * sizeof(float) - misalign) / sizeof(float) : 0);
}

glm::vec3 row3(const float* rows, std::size_t stride, int row, std::size_t k) {
  return {rows[row * stride + k], rows[(row + 1) * stride + k], rows[(row + 2) * stride + k]};
}

void set_row3(float* rows, std::size_t stride, int row, std::size_t k, const glm::vec3& a) {
  rows[row * stride + k] = a.x;
  rows[(row + 1) * stride + k] = a.y;
  rows[(row + 2) * stride + k] = a.z;
}

/// shade_batch where nothing reads the surface point: each triangle hit's continuation from
/// its material alone, the other hits one at a time.
void shade_materials_only(const Scene& scene, const BatchShading& how, const PathState* paths, const Hit* hits,
                          std::size_t n, int max_depth, std::vector<PathState>& next, std::vector<ShadowQuery>& shadows,
                          glm::vec3* sum) {
  const std::size_t triangles = scene.triangle_count();
  for (std::size_t i = 0; i < n; ++i) {
    const Hit& h = hits[i];
    if (!h.hit() || scene.prim_index(h) >= triangles) {
      sum[paths[i].pixel] += how.one(scene, paths[i], h, max_depth, next, shadows);
      continue;
    }
    SurfacePoint sp;
    sp.material = scene.triangle_materials()[scene.prim_index(h)];
    sum[paths[i].pixel] += how.then(scene, paths[i], sp, glm::vec3(0.0f), max_depth, next);
  }
}

/// Gathers the triangle hits into the lanes of `rows` (lane_of[i]: hit i's lane, or
/// kNotInLanes); misses, polygon hits and hits through instances (their vertices and error
/// bound are transformed: Scene::surface_as) stay out. Returns the lanes filled.
std::size_t gather_lanes(const Scene& scene, const PathState* paths, const Hit* hits, std::size_t n, float* rows,
                         std::size_t stride, std::uint32_t* lane_of) {
  const std::size_t triangles = scene.triangle_count();
  const glm::vec3* pos = scene.positions().data();
  const std::uint32_t* idx = scene.indices().data();
  std::size_t count = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Hit& h = hits[i];
    if (!h.hit() || scene.prim_index(h) >= triangles || h.inst != kInvalidId) {
      lane_of[i] = kNotInLanes;
      continue;
    }
    const std::uint32_t* t = idx + 3 * std::size_t(scene.prim_index(h));
    set_row3(rows, stride, kP0X, count, pos[t[0]]);
    set_row3(rows, stride, kP1X, count, pos[t[1]]);
    set_row3(rows, stride, kP2X, count, pos[t[2]]);
    rows[kU * stride + count] = h.u;
    rows[kV * stride + count] = h.v;
    const Ray& r = paths[i].ray;
    set_row3(rows, stride, kDirX, count, {r.dir[0], r.dir[1], r.dir[2]});
    lane_of[i] = std::uint32_t(count++);
  }
  return count;
}

/// Pads the lanes from `count` up to a multiple of `lanes` with a unit triangle seen by a
/// unit ray (no NaN, no subnormals to slow the lanes down); returns the padded count.
std::size_t pad_lanes(float* rows, std::size_t stride, std::size_t count, std::size_t lanes) {
  const std::size_t padded = (count + lanes - 1) / lanes * lanes;
  for (std::size_t k = count; k < padded; ++k) {
    set_row3(rows, stride, kP0X, k, {0.0f, 0.0f, 0.0f});
    set_row3(rows, stride, kP1X, k, {1.0f, 0.0f, 0.0f});
    set_row3(rows, stride, kP2X, k, {0.0f, 1.0f, 0.0f});
    rows[kU * stride + k] = rows[kV * stride + k] = 0.25f;
    set_row3(rows, stride, kDirX, k, {0.0f, 0.0f, 1.0f});
  }
  return padded;
}

/// Lane k's shadow rays, one per light that lights it, weighted by its Phong term.
void push_shadow_rays(const io::Material& m, const std::vector<io::PointLight>& lights, std::size_t light_count,
                      const PathState& path, const float* light_rows, std::size_t stride, std::size_t k,
                      std::vector<ShadowQuery>& shadows) {
  const bool specular = m.specular != glm::vec3(0.0f);
  if (m.diffuse == glm::vec3(0.0f) && !specular) return;
  for (std::size_t j = 0; j < light_count; ++j) {
    const float* l = light_rows + j * kLightRows * stride;
    const float n_dot_l = l[kNDotL * stride + k];
    if (n_dot_l <= 0.0f) continue;  // the light is behind the surface (NaN stays lit, as in the scalar test)
    glm::vec3 c = m.diffuse * n_dot_l;
    const float r_dot_v = l[kRDotV * stride + k];
    if (specular && r_dot_v > 0.0f) c += m.specular * std::pow(r_dot_v, m.shininess);
    const glm::vec3 o = row3(l, stride, kOrgX, k), d = row3(l, stride, kShadowX, k);
    shadows.push_back({Ray{{o.x, o.y, o.z}, 0.0f, {d.x, d.y, d.z}, 1.0f},
                       path.weight * c * lights[j].intensity / l[kDist2 * stride + k], path.pixel});
  }
}

}  // namespace

void shade_batch(const Scene& scene, const BatchShading& how, const PathState* paths, const Hit* hits, std::size_t n,
                 int max_depth, std::vector<PathState>& next, std::vector<ShadowQuery>& shadows, glm::vec3* sum) {
  const std::vector<io::PointLight>& lights = scene.lights();
  const std::size_t light_count = (how.stages & kShadows) != 0 ? lights.size() : 0;
  // Nothing reads the surface point (no lights, and a continuation that only needs the
  // material): skip the lanes altogether.
  if (light_count == 0 && !how.then_reads_surface) {
    shade_materials_only(scene, how, paths, hits, n, max_depth, next, shadows, sum);
    return;
  }
  const LaneKernels kernels = kernels_for(how.isa);
  // Per thread and reused: this runs once per bounce of every tile.
  thread_local std::vector<float> surface_buffer, light_buffer;
  thread_local std::vector<std::uint32_t> lane_of;
  const std::size_t stride = (n + kRowAlign - 1) / kRowAlign * kRowAlign;
  float* rows = aligned_floats(surface_buffer, kSurfaceRows * stride);
  lane_of.resize(n);
  const std::size_t count = gather_lanes(scene, paths, hits, n, rows, stride, lane_of.data());
  const std::size_t padded = pad_lanes(rows, stride, count, kernels.lanes);
  float* light_rows = aligned_floats(light_buffer, std::max<std::size_t>(1, light_count) * kLightRows * stride);
  if (padded != 0) {
    kernels.surfaces(rows, stride, padded);
    for (std::size_t j = 0; j < light_count; ++j) {
      const glm::vec3& p = lights[j].position;
      const float position[3] = {p.x, p.y, p.z};
      kernels.light(rows, stride, padded, position, light_rows + j * kLightRows * stride);
    }
  }

  // Write back in the one-at-a-time order: per path, its direct light, then its continuation.
  for (std::size_t i = 0; i < n; ++i) {
    const PathState& path = paths[i];
    const std::size_t k = lane_of[i];
    if (k == kNotInLanes) {
      sum[path.pixel] += how.one(scene, path, hits[i], max_depth, next, shadows);
      continue;
    }
    SurfacePoint sp;
    sp.material = scene.triangle_materials()[scene.prim_index(hits[i])];
    push_shadow_rays(scene.materials()[sp.material], lights, light_count, path, light_rows, stride, k, shadows);
    glm::vec3 view_dir(0.0f);
    if (how.then_reads_surface) {
      sp.p = row3(rows, stride, kPX, k);
      sp.p_error = row3(rows, stride, kErrX, k);
      sp.ng = sp.ns = row3(rows, stride, kNX, k);
      sp.front = rows[kFront * stride + k] != 0.0f;
      view_dir = row3(rows, stride, kViewX, k);
    }
    sum[path.pixel] += how.then(scene, path, sp, view_dir, max_depth, next);
  }
}

}  // namespace volley::render
