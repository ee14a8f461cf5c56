#include "accuracy/cases.h"

#include <algorithm>
#include <random>

#include "accuracy/closed_meshes.h"
#include "io/scene_loader.h"
#include "render/scene.h"
#include "render/workloads.h"

namespace volley::accuracy {
namespace {

/// `count` rays from uniform points of the box [lo - pad, hi + pad] aimed at interior points
/// of random triangles (barycentrics 0.1 .. 0.5 on two corners), t = 1 near the target.
std::vector<Ray> aimed_rays(const Mesh& mesh, std::size_t count, std::uint32_t seed) {
  std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (std::uint32_t v = 0; v < mesh.vertices(); ++v)
    for (int a = 0; a < 3; ++a)
      lo[a] = std::min(lo[a], mesh.position(v)[a]), hi[a] = std::max(hi[a], mesh.position(v)[a]);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Ray> rays;
  rays.reserve(count);
  while (rays.size() < count) {
    const auto t = static_cast<std::uint32_t>(rng() % mesh.triangles());
    const double b1 = 0.1 + 0.4 * u(rng), b2 = 0.1 + 0.4 * u(rng);
    float o[3], d[3];
    for (int c = 0; c < 3; ++c) {
      const double p = (1 - b1 - b2) * mesh.corner(t, 0)[c] + b1 * mesh.corner(t, 1)[c] + b2 * mesh.corner(t, 2)[c];
      const double pad = 0.5 * (hi[c] - lo[c]);
      o[c] = to_float(lo[c] - pad + (hi[c] - lo[c] + 2 * pad) * u(rng));
      d[c] = to_float(p - double(o[c]));
    }
    if (d[0] == 0.0f && d[1] == 0.0f && d[2] == 0.0f) continue;
    rays.push_back(make_ray(o, d));
  }
  return rays;
}

}  // namespace

std::size_t closed_case_count() { return 2 * std::size(kOffsets); }

Case closed_case(std::size_t k, std::size_t repeat) {
  const ClosedMesh c = k < std::size(kOffsets) ? grid_cube(8) : icosphere(3, 1000.0);
  const float offset = kOffsets[k % std::size(kOffsets)];
  Case out;
  out.set = "closed";
  out.name = c.name;
  out.offset = offset;
  out.closed = true;
  out.mesh = c.mesh.translated(offset);
  std::size_t origins = 0;
  out.rays = closed_mesh_rays(c, offset, out.exact_targets, origins, repeat);
  out.targets = c.targets.size();
  return out;
}

std::vector<Case> closed_cases(std::size_t repeat) {
  std::vector<Case> out;
  for (std::size_t k = 0; k < closed_case_count(); ++k) out.push_back(closed_case(k, repeat));
  return out;
}

std::vector<Case> random_triangle_cases(std::size_t rays) {
  std::vector<Case> out;
  for (float offset : kOffsets) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    Case k;
    k.set = "random";
    k.name = "triangles500";
    k.offset = offset;
    for (int i = 0; i < 500; ++i) {
      const double cx = u(rng), cy = u(rng), cz = u(rng), s = 0.1 + 0.9 * u(rng);
      const auto corner = [&] {
        return k.mesh.vertex(offset + cx + s * (u(rng) - 0.5), offset + cy + s * (u(rng) - 0.5),
                             offset + cz + s * (u(rng) - 0.5));
      };
      const std::uint32_t a = k.mesh.vertex(offset + cx, offset + cy, offset + cz);
      const std::uint32_t b = corner();
      const std::uint32_t c = corner();
      k.mesh.triangle(a, b, c);
    }
    k.rays = aimed_rays(k.mesh, rays, 23);
    out.push_back(std::move(k));
  }
  return out;
}

std::vector<Case> scene_cases(const std::filesystem::path& scenes_dir, int size, std::vector<std::string>& missing,
                              std::size_t max_meshes) {
  std::vector<Case> out;
  for (const char* file : kSceneMeshes) {
    if (out.size() >= 2 * max_meshes) break;
    const std::filesystem::path path = scenes_dir / file;
    if (!std::filesystem::exists(path)) {
      missing.push_back(path.string());
      continue;
    }
    const io::SceneDesc desc = io::load_scene(path, scenes_dir);
    Mesh mesh;
    for (const glm::vec3& p : desc.mesh.positions) mesh.xyz.insert(mesh.xyz.end(), {p.x, p.y, p.z});
    mesh.idx = desc.mesh.indices;
    const std::string stem = std::filesystem::path(file).stem().string();
    // The renderer's automatic camera frames the bare mesh; its primary rays in 4x4 blocks.
    const render::Scene scene(desc, size, size, Options{});
    Case primary;
    primary.set = "scene";
    primary.name = stem + "/primary";
    primary.rays = render::primary_rays(scene.camera());
    primary.mesh = mesh;
    Case random;
    random.set = "scene";
    random.name = stem + "/random";
    random.rays = aimed_rays(mesh, std::size_t(size) * std::size_t(size), 31);
    random.mesh = std::move(mesh);
    out.push_back(std::move(primary));
    out.push_back(std::move(random));
  }
  return out;
}

}  // namespace volley::accuracy
