// Shared by the BVH tests (test_bvh.cpp): triangle soups, brute force, the build's
// structural invariants, random rays and the shared meshes.
#pragma once
#include <doctest/doctest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>
#include "common/slab_grid.h"
#include "core/bbox.h"
#include "core/bvh.h"
#include "core/bvh_traverse.h"
#include "core/geometry.h"
#include "core/triangle.h"
#include "volley/options.h"

namespace bvh_test {

using namespace volley::core;
using Ray = volley::core::RayT<float>;
using TriHit = volley::core::TriHit<float>;

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr std::uint32_t kNoPrim = 0xffffffffu;

// A triangle soup: vertices 3i, 3i+1, 3i+2 make triangle i, intersected with `test`.
struct Soup {
  std::vector<glm::vec3> v;
  volley::TriangleTest test = volley::TriangleTest::moller;
  std::size_t size() const { return v.size() / 3; }
  void add(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
    v.push_back(a);
    v.push_back(b);
    v.push_back(c);
  }
  bool intersect(std::uint32_t prim, const Ray& ray, TriHit& hit) const {
    return volley::core::intersect_triangle(test, ray, v[3 * prim], v[3 * prim + 1], v[3 * prim + 2], hit);
  }
  std::vector<BBox> boxes() const {
    std::vector<BBox> b(size());
    for (std::size_t i = 0; i < size(); ++i)
      b[i] = volley::core::triangle_bbox(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
    return b;
  }
};

struct Answer {
  bool hit = false;
  float t = kInf;
  std::uint32_t prim = kNoPrim;
};

// Brute force: every triangle in index order, keeping the first among exact ties.
inline Answer brute_closest(const Soup& soup, Ray ray) {
  Answer a;
  for (std::uint32_t i = 0; i < soup.size(); ++i) {
    TriHit h;
    if (soup.intersect(i, ray, h)) {
      a = {true, h.t, i};
      ray.tmax = h.t;
    }
  }
  return a;
}

// The closest hit (AnyHit = false) or any hit of the BVH walk over the soup.
template <bool AnyHit>
Answer bvh_query(const Bvh& bvh, const Soup& soup, const Ray& ray) {
  Answer a;
  a.hit = volley::core::traverse<AnyHit>(bvh, ray, [&](std::uint32_t prim, float& tmax) {
    Ray r = ray;
    r.tmax = tmax;
    TriHit h;
    if (!soup.intersect(prim, r, h)) return false;
    tmax = h.t;
    a.t = h.t;
    a.prim = prim;
    return true;
  });
  return a;
}

inline Answer bvh_closest(const Bvh& bvh, const Soup& soup, const Ray& ray) { return bvh_query<false>(bvh, soup, ray); }
inline Answer bvh_any(const Bvh& bvh, const Soup& soup, const Ray& ray) { return bvh_query<true>(bvh, soup, ray); }

inline std::string describe(const Ray& r) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "org (%a, %a, %a) dir (%a, %a, %a) t [%a, %a)", r.org.x, r.org.y,
                r.org.z, r.dir.x, r.dir.y, r.dir.z, r.tmin, r.tmax);
  return buf;
}

struct Agreement {
  std::size_t rays = 0, hits = 0, misses = 0;
  std::size_t closest_wrong = 0, any_wrong = 0, tie_prims = 0;
};

// Closest and any hit against brute force for every ray. Closest: same hit/miss, same
// t bit for bit, same prim unless another prim ties at exactly that t. Any: same
// hit/miss, and the reported prim really is hit.
inline Agreement compare_with_brute_force(const Bvh& bvh, const Soup& soup, const std::vector<Ray>& rays) {
  Agreement g;
  for (const Ray& ray : rays) {
    ++g.rays;
    const Answer ref = brute_closest(soup, ray);
    (ref.hit ? g.hits : g.misses)++;
    const Answer got = bvh_closest(bvh, soup, ray);
    bool ok = got.hit == ref.hit;
    if (ok && ref.hit) {
      ok = got.t == ref.t;
      if (ok && got.prim != ref.prim) ++g.tie_prims;
    }
    if (!ok && g.closest_wrong++ < 3)
      MESSAGE("closest mismatch for ", describe(ray), ": brute ", ref.hit, " t=", ref.t, " prim ",
              ref.prim, ", bvh ", got.hit, " t=", got.t, " prim ", got.prim);

    const Answer any = bvh_any(bvh, soup, ray);
    TriHit h;
    const bool any_ok = any.hit == ref.hit && (!any.hit || soup.intersect(any.prim, ray, h));
    if (!any_ok && g.any_wrong++ < 3)
      MESSAGE("any-hit mismatch for ", describe(ray), ": brute ", ref.hit, ", bvh ", any.hit);
  }
  return g;
}

// Whether the exact ray meets the closed box over [tmin, tmax]: slab distances of the
// float inputs computed in double, with true divisions (a reference for the float
// slab test, independent of any triangle test).
inline bool box_touched(const BBox& b, const Ray& r) {
  if (b.empty()) return false;
  double t0 = r.tmin, t1 = r.tmax;
  for (int a = 0; a < 3; ++a) {
    const double d = r.dir[a];
    if (d == 0.0) {
      if (r.org[a] < b.lo[a] || r.org[a] > b.hi[a]) return false;
      continue;
    }
    double ta = (double(b.lo[a]) - r.org[a]) / d, tb = (double(b.hi[a]) - r.org[a]) / d;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return t0 <= t1;
}

// Traversal is conservative: with a leaf callback that never hits, every primitive
// whose box the exact ray touches must be handed to the callback. Returns the number
// of (ray, primitive) pairs missed, and counts the touched pairs.
inline std::size_t count_skipped_boxes(const Bvh& bvh, const std::vector<BBox>& boxes,
                                const std::vector<Ray>& rays, std::size_t& touched) {
  std::size_t skipped = 0;
  std::vector<char> visited(boxes.size());
  for (const Ray& ray : rays) {
    std::fill(visited.begin(), visited.end(), 0);
    volley::core::traverse<false>(bvh, ray, [&](std::uint32_t prim, float&) {
      visited[prim] = 1;
      return false;
    });
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      if (!box_touched(boxes[i], ray)) continue;
      ++touched;
      if (!visited[i] && skipped++ < 3) MESSAGE("box of prim ", i, " skipped for ", describe(ray));
    }
  }
  return skipped;
}

// Checks every structural invariant of a BVH built over `boxes`.
inline void check_structure(const Bvh& bvh, const std::vector<BBox>& boxes, const BvhBuildOptions& opt) {
  const std::size_t n = boxes.size();
  REQUIRE(bvh.prim_index.size() == n);
  if (n == 0) {
    CHECK(bvh.nodes.empty());
    return;
  }
  REQUIRE(!bvh.nodes.empty());
  std::vector<int> seen_prim(n, 0);
  std::vector<int> seen_node(bvh.nodes.size(), 0);
  std::vector<std::uint32_t> slot_owner(n, kNoPrim);
  std::size_t bad_child_box = 0, bad_leaf_box = 0, bad_leaf_size = 0, bad_index = 0;
  std::size_t leaves = 0, max_depth = 0;
  std::vector<std::pair<std::uint32_t, std::size_t>> stack{{0u, 0u}};
  seen_node[0] = 1;
  while (!stack.empty()) {
    const auto [i, depth] = stack.back();
    stack.pop_back();
    const BvhNode& node = bvh.nodes[i];
    max_depth = std::max(max_depth, depth);
    if (node.is_leaf()) {
      ++leaves;
      if (node.count > static_cast<std::uint32_t>(opt.max_leaf_size)) ++bad_leaf_size;
      if (std::size_t{node.first_or_child} + node.count > n) {
        ++bad_index;
        continue;
      }
      for (std::uint32_t k = node.first_or_child; k < node.first_or_child + node.count; ++k) {
        if (slot_owner[k] != kNoPrim) ++bad_index;  // two leaves share a slot
        slot_owner[k] = i;
        const std::uint32_t prim = bvh.prim_index[k];
        if (prim >= n) {
          ++bad_index;
          continue;
        }
        ++seen_prim[prim];
        if (!node.box.contains(boxes[prim])) ++bad_leaf_box;
      }
    } else {
      const std::uint32_t c = node.first_or_child;
      if (c == 0 || std::size_t{c} + 1 >= bvh.nodes.size()) {
        ++bad_index;
        continue;
      }
      for (std::uint32_t k : {c, c + 1}) {
        if (seen_node[k]++) ++bad_index;  // a node reached twice: not a tree
        if (!node.box.contains(bvh.nodes[k].box)) ++bad_child_box;
        stack.push_back({k, depth + 1});
      }
    }
  }
  CHECK(bad_index == 0);
  CHECK(bad_child_box == 0);
  CHECK(bad_leaf_box == 0);
  CHECK(bad_leaf_size == 0);
  CHECK(max_depth < static_cast<std::size_t>(kBvhMaxDepth));
  CHECK(std::count(seen_prim.begin(), seen_prim.end(), 1) == static_cast<long>(n));
  CHECK(std::count(seen_node.begin(), seen_node.end(), 1) == static_cast<long>(bvh.nodes.size()));
  CHECK(bvh.nodes.size() == 2 * leaves - 1);
  const auto stats = volley::core::bvh_stats(bvh, opt);
  CHECK(stats.nodes == bvh.nodes.size());
  CHECK(stats.leaves == leaves);
  CHECK(stats.depth == max_depth);
}

// Random soup of n triangles in [-1, 1]^3, edge lengths about the mean spacing.
inline Soup random_soup(std::size_t n, std::mt19937& rng) {
  std::uniform_real_distribution<float> pos(-1.0f, 1.0f);
  const float s = 2.0f / std::cbrt(static_cast<float>(n));
  std::uniform_real_distribution<float> off(-s, s);
  Soup soup;
  for (std::size_t i = 0; i < n; ++i) {
    const glm::vec3 c(pos(rng), pos(rng), pos(rng));
    soup.add(c + glm::vec3(off(rng), off(rng), off(rng)), c + glm::vec3(off(rng), off(rng), off(rng)),
             c + glm::vec3(off(rng), off(rng), off(rng)));
  }
  return soup;
}

// Rays from a box around `bounds`: half aimed at random points inside it (mostly hits),
// half in random directions (many misses); some with a finite tmax.
inline std::vector<Ray> random_rays(const BBox& bounds, std::size_t n, std::mt19937& rng) {
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  const glm::vec3 d = bounds.diagonal();
  auto point_in = [&](float grow) {
    return bounds.lo - grow * d + (1.0f + 2.0f * grow) * glm::vec3(unit(rng), unit(rng), unit(rng)) * d;
  };
  std::vector<Ray> rays(n);
  for (std::size_t i = 0; i < n; ++i) {
    const glm::vec3 org = point_in(0.5f);
    glm::vec3 dir = i % 2 == 0 ? point_in(0.0f) - org
                               : glm::vec3(unit(rng) - 0.5f, unit(rng) - 0.5f, unit(rng) - 0.5f);
    const float tmax = i % 5 == 4 ? unit(rng) * 2.0f : kInf;
    rays[i] = {org, 0.0f, dir, tmax};
  }
  return rays;
}

inline BBox bounds_of(const std::vector<BBox>& boxes) {
  BBox b;
  for (const BBox& x : boxes) b.extend(x);
  return b;
}

// Builds the soup's BVH, checks its structure, and checks 1000 random rays through its
// bounds against brute force (some of them hit).
inline void check_random_rays(const Soup& soup, std::mt19937& rng) {
  const auto boxes = soup.boxes();
  const Bvh bvh = volley::core::build_bvh(boxes);
  check_structure(bvh, boxes, {});
  const Agreement g = compare_with_brute_force(bvh, soup, random_rays(bounds_of(boxes), 1000, rng));
  CHECK(g.hits > 0);
  CHECK(g.closest_wrong == 0);
  CHECK(g.any_wrong == 0);
}

// Tiny OBJ reader for the shared meshes: `v x y z` and `f a b c ...` lines only
// (a/b/c and negative indices tolerated, polygons fan-triangulated). Empty soup when
// the file is missing.
inline Soup read_obj(const std::string& path) {
  Soup soup;
  std::ifstream in(path);
  if (!in) return soup;
  std::vector<glm::vec3> verts;
  std::string line;
  std::vector<long> face;
  while (std::getline(in, line)) {
    if (line.size() < 2 || line[1] != ' ') continue;
    std::istringstream ls(line.substr(2));
    if (line[0] == 'v') {
      glm::vec3 p;
      ls >> p.x >> p.y >> p.z;
      verts.push_back(p);
    } else if (line[0] == 'f') {
      face.clear();
      std::string tok;
      while (ls >> tok) {
        const long k = std::stol(tok.substr(0, tok.find('/')));
        face.push_back(k > 0 ? k - 1 : static_cast<long>(verts.size()) + k);
      }
      for (std::size_t k = 2; k < face.size(); ++k)
        soup.add(verts.at(face[0]), verts.at(face[k - 1]), verts.at(face[k]));
    }
  }
  return soup;
}

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace bvh_test
