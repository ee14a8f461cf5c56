#include "accuracy/query_checks.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <iterator>
#include <random>

#include "accuracy/closed_meshes.h"
#include "core/point_triangle.h"
#include "volley/accel.h"

namespace volley::accuracy {
namespace {

Accel accel_of(const Mesh& m, float offset, Isa isa) {
  std::vector<float> xyz = m.xyz;
  for (float& x : xyz) x = to_float(double(x) + offset);
  Accel a;
  a.add_triangles(xyz.data(), m.vertices(), m.idx.data(), m.triangles());
  a.commit(Options{TriangleTest::watertight, isa});
  return a;
}

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

/// Nearest distance from p to the mesh in double, by brute force.
double reference_distance(const Mesh& m, const std::array<double, 3>& p) {
  double best = INFINITY;
  for (std::size_t t = 0; t < m.triangles(); ++t) {
    const auto a = m.position(m.idx[3 * t]), b = m.position(m.idx[3 * t + 1]), c = m.position(m.idx[3 * t + 2]);
    const auto r = core::nearest_on_triangle<double, core::ScalarLaneOps<double>>(
        p[0] - a[0], p[1] - a[1], p[2] - a[2], b[0] - a[0], b[1] - a[1], b[2] - a[2], c[0] - a[0], c[1] - a[1],
        c[2] - a[2]);
    best = std::min(best, r.d2);
  }
  return std::sqrt(best);
}

/// Points of a closed mesh for contains and distances, with the reference answers.
struct Sample {
  const ClosedMesh* mesh;
  std::vector<float> xyz;
  std::vector<std::uint8_t> inside;
  std::vector<double> distance;
};

/// 2000 points in the bounds of `c`, kept only when farther than 1e-6 of the size from the
/// surface (where the reference is sure). `box`: c is the grid cube, whose inside is its
/// exact box (grid_cube winds opposite faces alike); otherwise the winding number decides.
Sample sample_points(const ClosedMesh& c, bool box, std::mt19937& rng) {
  Sample s{&c, {}, {}, {}};
  std::uniform_real_distribution<double> u(-0.2 * c.size, 2.2 * c.size);
  while (s.inside.size() < 2000) {
    const std::array<double, 3> p{to_float(u(rng)), to_float(u(rng)), to_float(u(rng))};
    const double d = reference_distance(c.mesh, p);
    if (d < 1e-6 * c.size) continue;
    s.xyz.insert(s.xyz.end(), {float(p[0]), float(p[1]), float(p[2])});
    s.inside.push_back(box ? c.depth(p, c.size) > 0 : std::lround(winding_number(c.mesh, p)) != 0);
    s.distance.push_back(d);
  }
  return s;
}

/// Crossing parity on `isa`: rays from inside each closed mesh (aimed, then random
/// directions from the same origins) at offsets 0 to 1e6, unbounded; an even count is wrong.
void check_parity(const ClosedMesh* meshes, std::size_t mesh_count, Isa isa, std::mt19937& rng, QueryRow& row) {
  double count_s = 0;
  for (std::size_t m = 0; m < mesh_count; ++m)
    for (float offset : {0.0f, 1e3f, 1e5f, 1e6f}) {
      const ClosedMesh& c = meshes[m];
      std::size_t exact = 0, origins = 0;
      std::vector<Ray> rays = closed_mesh_rays(c, offset, exact, origins);
      for (Ray& r : rays) r.tmax = kInf;
      std::normal_distribution<float> g;
      const std::size_t aimed = rays.size();
      for (std::size_t k = 0; k < 2000; ++k) {
        Ray r = rays[(k * 7919) % aimed];
        r.dir[0] = g(rng), r.dir[1] = g(rng), r.dir[2] = g(rng);
        rays.push_back(r);
      }
      const Accel a = accel_of(c.mesh, offset, isa);
      const auto start = std::chrono::steady_clock::now();
      for (const Ray& r : rays) row.parity_errors += a.count_intersections(r) % 2 == 0;
      count_s += seconds_since(start);
      row.parity_rays += rays.size();
    }
  row.count_ns = row.parity_rays ? count_s / double(row.parity_rays) * 1e9 : 0;
}

/// Axis-aligned rays from inside the box mesh through its grid's vertices and edges: one
/// crossing each.
void check_box_rays(const ClosedMesh& box, Isa isa, QueryRow& row) {
  const Accel cube = accel_of(box.mesh, 0.0f, isa);
  for (int i = 1; i < 8; ++i)
    for (int j = 1; j < 8; ++j)
      for (int axis = 0; axis < 3; ++axis)
        for (float sign : {1.0f, -1.0f}) {
          float o[3], d[3] = {0, 0, 0};
          o[axis] = 2.25f, o[(axis + 1) % 3] = 0.5f * i, o[(axis + 2) % 3] = 0.5f * j;
          d[axis] = sign;
          row.box_errors += cube.count_intersections(Ray{{o[0], o[1], o[2]}, 0.0f, {d[0], d[1], d[2]}, kInf}) != 1;
          ++row.box_rays;
        }
}

/// contains and distances on `isa` against the samples' reference answers.
void check_points(const std::vector<Sample>& samples, Isa isa, QueryRow& row) {
  double distance_s = 0;
  for (const Sample& s : samples) {
    const Accel a = accel_of(s.mesh->mesh, 0.0f, isa);
    const std::size_t n = s.inside.size();
    std::vector<std::uint8_t> inside(n);
    a.contains(s.xyz.data(), n, inside.data(), 1);
    std::vector<float> d(n);
    const auto start = std::chrono::steady_clock::now();
    a.distances(s.xyz.data(), n, d.data(), false, 1);
    distance_s += seconds_since(start);
    for (std::size_t i = 0; i < n; ++i) {
      row.contains_errors += inside[i] != s.inside[i];
      const double err = std::abs(double(d[i]) - s.distance[i]) / (0x1p-24 * (s.distance[i] + s.mesh->size));
      row.distance_error_max = std::max(row.distance_error_max, err);
    }
    row.contains_points += n;
    row.distance_points += n;
  }
  row.distance_ns = row.distance_points ? distance_s / double(row.distance_points) * 1e9 : 0;
}

}  // namespace

std::vector<QueryRow> run_query_checks(const std::vector<Isa>& isas) {
  const ClosedMesh meshes[] = {grid_cube(4), icosphere(2, 40.0), icosphere(3, 200.0)};
  const ClosedMesh box = grid_cube(4);
  std::mt19937 rng(29);
  std::vector<Sample> samples;
  samples.push_back(sample_points(meshes[0], true, rng));
  samples.push_back(sample_points(meshes[1], false, rng));
  std::vector<QueryRow> rows;
  for (Isa isa : isas) {
    QueryRow row;
    row.isa = isa;
    check_parity(meshes, std::size(meshes), isa, rng, row);
    check_box_rays(box, isa, row);
    check_points(samples, isa, row);
    rows.push_back(row);
  }
  return rows;
}

}  // namespace volley::accuracy
