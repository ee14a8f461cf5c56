#include "accuracy/closed_meshes.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <utility>

namespace volley::accuracy {

ClosedMesh grid_cube(int n) {
  ClosedMesh c;
  c.name = "cube" + std::to_string(n);
  c.size = n;
  std::map<std::array<int, 3>, std::uint32_t> ids;
  const auto vid = [&](std::array<int, 3> p) {
    auto it = ids.find(p);
    if (it != ids.end()) return it->second;
    const std::uint32_t v = c.mesh.vertex(p[0], p[1], p[2]);
    ids.emplace(p, v);
    return v;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int level : {0, n})
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          const auto at = [&](int a, int b) {
            std::array<int, 3> p{};
            p[axis] = level, p[(axis + 1) % 3] = a, p[(axis + 2) % 3] = b;
            return vid(p);
          };
          const std::uint32_t v00 = at(i, j), v10 = at(i + 1, j), v11 = at(i + 1, j + 1), v01 = at(i, j + 1);
          if ((i + j) % 2) {
            c.mesh.triangle(v00, v10, v11), c.mesh.triangle(v00, v11, v01);
          } else {
            c.mesh.triangle(v00, v10, v01), c.mesh.triangle(v10, v11, v01);
          }
        }
  for (int axis = 0; axis < 3; ++axis)
    for (int level : {0, n})
      for (int i = 0; i <= 2 * n; ++i)
        for (int j = 0; j <= 2 * n; ++j) {
          std::array<double, 3> p{};
          p[axis] = level, p[(axis + 1) % 3] = 0.5 * i, p[(axis + 2) % 3] = 0.5 * j;
          c.targets.push_back(p);
        }
  c.depth = [](const std::array<double, 3>& p, double size) {
    double d = 1e300;
    for (double x : p) d = std::min({d, x, size - x});
    return d;
  };
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(0.05 * n, 0.95 * n);
  c.origins = {
      {0.5 * n + 0.1234, 0.5 * n - 0.0567, 0.5 * n + 0.0089}, {0.3, 0.25 * n, 0.7 * n}, {n - 0.21, n - 0.33, 0.4}};
  for (int k = 0; k < 9; ++k) c.origins.push_back({u(rng), u(rng), u(rng)});
  return c;
}

ClosedMesh icosphere(int levels, double radius) {
  ClosedMesh c;
  c.name = "icosphere" + std::to_string(levels);
  c.size = radius;
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<std::array<double, 3>> p = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                                          {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<std::uint32_t, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                                 {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                                 {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                                 {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  const auto normalize = [](std::array<double, 3> a) {
    const double l = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    return std::array<double, 3>{a[0] / l, a[1] / l, a[2] / l};
  };
  for (auto& q : p) q = normalize(q);
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    const auto m = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      p.push_back(normalize({p[a][0] + p[b][0], p[a][1] + p[b][1], p[a][2] + p[b][2]}));
      const auto id = static_cast<std::uint32_t>(p.size() - 1);
      mid.emplace(key, id);
      return id;
    };
    std::vector<std::array<std::uint32_t, 3>> g;
    for (const auto& tri : f) {
      const std::uint32_t a = m(tri[0], tri[1]), b = m(tri[1], tri[2]), cc = m(tri[2], tri[0]);
      g.push_back({tri[0], a, cc}), g.push_back({tri[1], b, a}), g.push_back({tri[2], cc, b}), g.push_back({a, b, cc});
    }
    f = std::move(g);
  }
  for (const auto& q : p)
    c.mesh.vertex(std::round(radius * (1 + q[0])), std::round(radius * (1 + q[1])), std::round(radius * (1 + q[2])));
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
  for (const auto& tri : f) {
    c.mesh.triangle(tri[0], tri[1], tri[2]);
    for (int k = 0; k < 3; ++k) edges[std::minmax(tri[k], tri[(k + 1) % 3])]++;
  }
  for (std::uint32_t v = 0; v < c.mesh.vertices(); ++v) c.targets.push_back(c.mesh.position(v));
  for (const auto& [e, count] : edges) {
    const auto a = c.mesh.position(e.first), b = c.mesh.position(e.second);
    c.targets.push_back({0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])});
  }
  c.depth = [](const std::array<double, 3>& q, double r) {
    const double dx = q[0] - r, dy = q[1] - r, dz = q[2] - r;
    return 0.9 * r - std::sqrt(dx * dx + dy * dy + dz * dz);  // the faceted sphere contains the 0.9 r ball
  };
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.45 * radius, 0.45 * radius);
  c.origins = {{radius + 0.123, radius - 0.0456, radius + 0.0789}};
  for (int k = 0; k < 7; ++k) c.origins.push_back({radius + u(rng), radius + u(rng), radius + u(rng)});
  return c;
}

std::vector<Ray> closed_mesh_rays(const ClosedMesh& c, float offset, std::size_t& exact_targets,
                                  std::size_t& origins_used, std::size_t repeat) {
  std::vector<Ray> rays;
  exact_targets = 0;
  std::vector<std::array<float, 3>> targets;
  for (const auto& t : c.targets) {
    std::array<float, 3> f{};
    bool exact = true;
    for (int a = 0; a < 3; ++a) {
      f[a] = to_float(t[a] + double(offset));
      exact &= double(f[a]) == t[a] + double(offset);
    }
    exact_targets += exact;
    targets.push_back(f);
  }
  std::vector<std::array<double, 3>> origins = c.origins;
  std::mt19937 rng(99);
  std::uniform_real_distribution<double> u(0.0, 2.0 * c.size);
  while (origins.size() < c.origins.size() * repeat) {  // more interior origins
    const std::array<double, 3> p{u(rng), u(rng), u(rng)};
    if (c.depth(p, c.size) > 0.05 * c.size) origins.push_back(p);
  }
  origins_used = 0;
  rays.reserve(origins.size() * targets.size());
  for (const auto& o : origins) {
    float of[3];
    std::array<double, 3> back{};
    for (int a = 0; a < 3; ++a) {
      of[a] = to_float(o[a] + double(offset));
      back[a] = double(of[a]) - double(offset);
    }
    if (c.depth(back, c.size) <= 0.0) continue;  // rounding moved it onto or out of the surface
    ++origins_used;
    for (const auto& t : targets) {
      const float d[3] = {t[0] - of[0], t[1] - of[1], t[2] - of[2]};
      rays.push_back(make_ray(of, d));
    }
  }
  return rays;
}

double winding_number(const Mesh& m, const std::array<double, 3>& p) {
  double sum = 0.0;
  for (std::size_t t = 0; t < m.triangles(); ++t) {
    double v[3][3];
    for (int k = 0; k < 3; ++k) {
      const auto c = m.corner(std::uint32_t(t), k);
      for (int a = 0; a < 3; ++a) v[k][a] = c[a] - p[a];
    }
    auto dot = [&](int i, int j) { return v[i][0] * v[j][0] + v[i][1] * v[j][1] + v[i][2] * v[j][2]; };
    const double la = std::sqrt(dot(0, 0)), lb = std::sqrt(dot(1, 1)), lc = std::sqrt(dot(2, 2));
    const double det = v[0][0] * (v[1][1] * v[2][2] - v[1][2] * v[2][1]) - v[0][1] * (v[1][0] * v[2][2] - v[1][2] * v[2][0]) +
                       v[0][2] * (v[1][0] * v[2][1] - v[1][1] * v[2][0]);
    sum += 2.0 * std::atan2(det, la * lb * lc + dot(0, 1) * lc + dot(0, 2) * lb + dot(1, 2) * la);
  }
  return sum / (4.0 * M_PI);
}

}  // namespace volley::accuracy
