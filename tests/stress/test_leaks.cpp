// Numerical stress suite (docs/accuracy.md, stress catalogue) — closed-mesh leaks.
//
// Items 1, 2, 8 and 13: closed indexed meshes (a subdivided grid cube and an integer-vertex
// icosphere), rays from interior points aimed exactly at shared vertices, edge midpoints and
// quad diagonals, through the public Accel API with the shipped build flags (FMA on in the
// AVX2 / AVX-512 objects), for the scalar oracle and every ISA this CPU has, in every query
// mode (single ray, packets of 4, 8, 16, stream; closest hit and occlusion), with the mesh
// moved by 0, 1e2, 1e3, 1e5, 1e6, 1e7. A ray from inside a closed mesh must hit: a miss is
// a leak. Also the shared dragon_100k.obj (rays at vertices and exactly representable edge
// midpoints that are not on the silhouette seen from the origin).
//
// Exact-target rule: targets have half-integer coordinates (the cube spans [0, 8], the
// icosphere [0, 2000]); moved by `offset` they stay exactly representable while
// offset + extent < 2^23 (8.4e6). At 1e7 half-integers round (vertices stay exact): the
// rays then pass next to the edges, not through them; they must still hit (closed mesh).
//
// Long mode: VOLLEY_STRESS_LONG=1 multiplies the interior origins (millions of rays per
// ISA); the default runs a few hundred thousand rays in total for CI.
#include <doctest/doctest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>

#include "closed_meshes.h"
#include "stress_util.h"

using namespace stress;

namespace {

const float kOffsets[] = {0.0f, 1e2f, 1e3f, 1e5f, 1e6f, 1e7f};

struct ModeLeaks {
  std::size_t hit_leaks = 0, occluded_leaks = 0, nan = 0;
};

ModeLeaks count_leaks(const Answers& a) {
  ModeLeaks l;
  for (std::size_t i = 0; i < a.hits.size(); ++i) {
    l.hit_leaks += !a.hits[i].hit();
    l.occluded_leaks += !a.occluded[i];
    l.nan += std::isnan(a.hits[i].t) || std::isnan(a.hits[i].u) || std::isnan(a.hits[i].v);
  }
  return l;
}

void run_closed_mesh(const ClosedMesh& c) {
  const std::size_t repeat = long_mode() ? 50 : 1;  // long: ~1M rays per mesh, offset, test, ISA and mode
  for (float offset : kOffsets) {
    std::size_t exact = 0, origins = 0;
    const std::vector<Ray> rays = closed_mesh_rays(c, offset, exact, origins, repeat);
    REQUIRE(origins > 0);
    const Mesh moved = c.mesh.translated(offset);
    for (TriangleTest test : kTests) {
      // Single-ray hit/miss of the first ISA of each agreement group: the scalar oracle, or
      // for fused moller the first of AVX2, AVX-512 (item 13).
      std::vector<std::uint8_t> reference_hit[kAgreementGroups];
      for (Isa isa : isas()) {
        const Accel accel = moved.accel(test, isa);
        const int group = agreement_group(test, isa);
        std::ostringstream row;
        row << c.name << " offset " << offset << " " << name(test) << " " << name(isa) << ": " << rays.size()
            << " rays (" << origins << " origins, exact targets " << exact << "/" << c.targets.size()
            << "), leaks intersect/occluded:";
        std::size_t disagree = 0, total_leaks = 0, nan = 0;
        for (Mode mode : kModes) {
          const Answers a = trace(accel, rays, mode);
          const ModeLeaks l = count_leaks(a);
          row << " " << name(mode) << " " << l.hit_leaks << "/" << l.occluded_leaks;
          total_leaks += l.hit_leaks + l.occluded_leaks;
          nan += l.nan;
          if (reference_hit[group].empty()) {
            for (const Hit& h : a.hits) reference_hit[group].push_back(h.hit());
          } else {
            for (std::size_t i = 0; i < rays.size(); ++i) disagree += a.hits[i].hit() != bool(reference_hit[group][i]);
          }
          // Occlusion agrees with closest hit in every mode.
          std::size_t occ_mismatch = 0;
          for (std::size_t i = 0; i < rays.size(); ++i) occ_mismatch += a.hits[i].hit() != bool(a.occluded[i]);
          CHECK_MESSAGE(occ_mismatch == 0, row.str());
        }
        MESSAGE(row.str());
        CHECK_MESSAGE(nan == 0, row.str());
        // Item 13: same hit/miss as the group's single rays, ray by ray.
        CHECK_MESSAGE(disagree == 0, row.str() << " — hit/miss differs from the single rays of " << group_name(group)
                                               << " in " << disagree);
        if (test == TriangleTest::watertight) CHECK_MESSAGE(total_leaks == 0, row.str());
      }
    }
  }
}

/// Minimal OBJ reader (v and f, fan-triangulated; other statements ignored).
bool read_obj(const std::filesystem::path& file, Mesh& mesh) {
  std::ifstream in(file);
  if (!in) return false;
  std::string line;
  while (std::getline(in, line)) {
    if (line.size() < 2) continue;
    std::istringstream s(line);
    std::string tag;
    s >> tag;
    if (tag == "v") {
      double x, y, z;
      s >> x >> y >> z;
      mesh.vertex(x, y, z);
    } else if (tag == "f") {
      std::vector<std::uint32_t> f;
      std::string tok;
      while (s >> tok) {
        const long i = std::stol(tok.substr(0, tok.find('/')));
        f.push_back(static_cast<std::uint32_t>(i > 0 ? i - 1 : long(mesh.vertices()) + i));
      }
      for (std::size_t k = 2; k < f.size(); ++k) mesh.triangle(f[0], f[k - 1], f[k]);
    }
  }
  return true;
}

}  // namespace

TEST_CASE("stress 1/2/8/13: closed grid cube with rays at shared vertices and edges and diagonals at offsets to 1e7") {
  run_closed_mesh(grid_cube(8));
}

TEST_CASE("stress 1/2/8/13: closed integer icosphere with rays at shared vertices and edge midpoints at offsets to 1e7") {
  run_closed_mesh(icosphere(3, 1000.0));
}

TEST_CASE("stress 14: closed-mesh generators cover every face and both signs of direction with exact targets") {
  for (const ClosedMesh& c : {grid_cube(8), icosphere(3, 1000.0)}) {
    std::size_t exact = 0, origins = 0;
    const std::vector<Ray> rays = closed_mesh_rays(c, 0.0f, exact, origins);
    CHECK(exact == c.targets.size());
    CHECK(origins == c.origins.size());
    Coverage cov[3];
    for (const Ray& r : rays)
      for (int a = 0; a < 3; ++a) cov[a].add(r.dir[a]);
    for (int a = 0; a < 3; ++a) {
      CHECK(cov[a].negative);
      CHECK(cov[a].positive);
    }
    // At 1e7 the vertices stay exact but half-integer targets do not (the stated rule).
    const std::vector<Ray> far = closed_mesh_rays(c, 1e7f, exact, origins);
    CHECK(exact >= c.mesh.vertices() / 2);
    CHECK(exact < c.targets.size());
    CHECK(origins > 0);
    // Every target is on the surface: the scalar oracle's watertight test hits at t <= 1.
    const Accel accel = c.mesh.accel(TriangleTest::watertight, Isa::scalar);
    std::size_t beyond = 0;
    for (const Ray& r : rays) beyond += !(accel.intersect(r).t <= 1.0f + 1e-5f);
    CHECK(beyond == 0);
  }
}

TEST_CASE("stress 1/13: dragon_100k.obj is watertight through the whole BVH at vertices and exact edge midpoints") {
  const std::filesystem::path file = std::filesystem::path(VOLLEY_SHARED_SCENES) / "dragon_100k.obj";
  if (!std::filesystem::exists(file)) {
    MESSAGE("skipped: " << file << " not present");
    return;
  }
  Mesh mesh;
  REQUIRE(read_obj(file, mesh));
  REQUIRE(mesh.triangles() > 0);
  // Edges shared by exactly two triangles, with their opposite vertices.
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::uint32_t>> edges;
  for (std::size_t t = 0; t < mesh.triangles(); ++t)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = mesh.idx[3 * t + k], b = mesh.idx[3 * t + (k + 1) % 3], c = mesh.idx[3 * t + (k + 2) % 3];
      edges[std::minmax(a, b)].push_back(c);
    }
  std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (std::uint32_t v = 0; v < mesh.vertices(); ++v)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], mesh.position(v)[a]), hi[a] = std::max(hi[a], mesh.position(v)[a]);
  using V = std::array<double, 3>;
  const auto det = [](const V& o, const V& a, const V& b, const V& c) {
    const V x{a[0] - o[0], a[1] - o[1], a[2] - o[2]}, y{b[0] - o[0], b[1] - o[1], b[2] - o[2]},
        z{c[0] - o[0], c[1] - o[1], c[2] - o[2]};
    const double d = x[0] * (y[1] * z[2] - y[2] * z[1]) - x[1] * (y[0] * z[2] - y[2] * z[0]) + x[2] * (y[0] * z[1] - y[1] * z[0]);
    const auto len = [](const V& w) { return std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]); };
    return d / (len(x) * len(y) * len(z) + 1e-300);
  };
  // Origins: points of the bounding box (inside or outside the dragon: the criterion below
  // does not need interior points). A ray aimed exactly at a point p of a manifold edge that
  // is not a silhouette seen from the origin (the two opposite vertices on opposite sides of
  // the plane through origin and edge, by a clear margin) must hit something at t <= 1: the
  // two triangles cover a neighbourhood of p as seen from the origin. The same holds for a
  // vertex all of whose edges are such edges (its fan covers a neighbourhood of it). Targets:
  // those vertices, and those edges' midpoints where exactly representable.
  std::mt19937 rng(7);
  const int n_origins = long_mode() ? 100 : 3;
  std::vector<std::uint32_t> degree(mesh.vertices(), 0), good_edges(mesh.vertices(), 0);
  for (const auto& [edge, opposite] : edges) ++degree[edge.first], ++degree[edge.second];
  std::vector<Ray> rays;
  std::size_t skipped_silhouette = 0, inexact = 0, vertex_rays = 0;
  for (int k = 0; k < n_origins; ++k) {
    float of[3];
    V o{};
    for (int a = 0; a < 3; ++a) {
      std::uniform_real_distribution<double> u(lo[a], hi[a]);
      of[a] = to_float(u(rng));
      o[a] = of[a];
    }
    std::fill(good_edges.begin(), good_edges.end(), 0u);
    for (const auto& [edge, opposite] : edges) {
      const V a = mesh.position(edge.first), b = mesh.position(edge.second);
      bool good = opposite.size() == 2;
      if (good) {
        const double s1 = det(o, a, b, mesh.position(opposite[0])), s2 = det(o, a, b, mesh.position(opposite[1]));
        good = s1 * s2 < 0 && std::min(std::fabs(s1), std::fabs(s2)) > 1e-4;
      }
      if (!good) {
        ++skipped_silhouette;
        continue;
      }
      ++good_edges[edge.first], ++good_edges[edge.second];
      float m[3];
      bool exact = true;
      for (int c = 0; c < 3; ++c) {
        m[c] = to_float(0.5 * (a[c] + b[c]));
        exact &= double(m[c]) == 0.5 * (a[c] + b[c]);
      }
      if (!exact) {
        ++inexact;
        continue;
      }
      const float d[3] = {m[0] - of[0], m[1] - of[1], m[2] - of[2]};
      rays.push_back(make_ray(of, d));
    }
    for (std::uint32_t v = 0; v < mesh.vertices(); ++v) {
      if (degree[v] == 0 || good_edges[v] != degree[v]) continue;
      const float d[3] = {mesh.xyz[3 * v] - of[0], mesh.xyz[3 * v + 1] - of[1], mesh.xyz[3 * v + 2] - of[2]};
      rays.push_back(make_ray(of, d));
      ++vertex_rays;
    }
  }
  REQUIRE(rays.size() > 100);
  for (Isa isa : isas()) {
    const Accel accel = mesh.accel(TriangleTest::watertight, isa);
    std::ostringstream row;
    row << "dragon_100k watertight " << name(isa) << ": " << rays.size() << " rays (" << vertex_rays << " at vertices, "
        << rays.size() - vertex_rays << " at edge midpoints; " << inexact << " inexact midpoints and "
        << skipped_silhouette << " silhouette/non-manifold edges left out), leaks (t > 1 + 1e-4 or miss / not occluded):";
    std::size_t total = 0;
    for (Mode mode : kModes) {
      const Answers a = trace(accel, rays, mode);
      std::size_t leaks = 0, occ = 0;
      for (std::size_t i = 0; i < rays.size(); ++i) {
        leaks += !(a.hits[i].t <= 1.0f + 1e-4f);
        occ += !a.occluded[i];  // the target is hit before tmax = inf
      }
      row << " " << name(mode) << " " << leaks << "/" << occ;
      total += leaks + occ;
    }
    MESSAGE(row.str());
    CHECK_MESSAGE(total == 0, row.str());
  }
}
