// The scalar BVH (bbox.h, bvh.h, bvh_build.cpp, bvh_traverse.h): structural invariants
// of the binned-SAH build, and closest-hit / any-hit traversal against brute force over
// every primitive, on random soups, axis-aligned grids with rays on slab planes
// (docs/accuracy.md stress item 4), degenerate inputs and the shared benchmark meshes.
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

namespace {

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
Answer brute_closest(const Soup& soup, Ray ray) {
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

Answer bvh_closest(const Bvh& bvh, const Soup& soup, const Ray& ray) { return bvh_query<false>(bvh, soup, ray); }
Answer bvh_any(const Bvh& bvh, const Soup& soup, const Ray& ray) { return bvh_query<true>(bvh, soup, ray); }

std::string describe(const Ray& r) {
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
Agreement compare_with_brute_force(const Bvh& bvh, const Soup& soup, const std::vector<Ray>& rays) {
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
bool box_touched(const BBox& b, const Ray& r) {
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
std::size_t count_skipped_boxes(const Bvh& bvh, const std::vector<BBox>& boxes,
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
void check_structure(const Bvh& bvh, const std::vector<BBox>& boxes, const BvhBuildOptions& opt) {
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
Soup random_soup(std::size_t n, std::mt19937& rng) {
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
std::vector<Ray> random_rays(const BBox& bounds, std::size_t n, std::mt19937& rng) {
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

BBox bounds_of(const std::vector<BBox>& boxes) {
  BBox b;
  for (const BBox& x : boxes) b.extend(x);
  return b;
}

// Builds the soup's BVH, checks its structure, and checks 1000 random rays through its
// bounds against brute force (some of them hit).
void check_random_rays(const Soup& soup, std::mt19937& rng) {
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
Soup read_obj(const std::string& path) {
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

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

TEST_CASE("bvh: BBox extend, emptiness, area and containment") {
  BBox b;
  CHECK(b.empty());
  CHECK(b.half_area() == 0.0f);
  b.extend(glm::vec3(1, 2, 3));
  CHECK(!b.empty());
  CHECK(b.half_area() == 0.0f);  // a point
  b.extend(glm::vec3(2, 4, 7));
  CHECK(b.lo == glm::vec3(1, 2, 3));
  CHECK(b.hi == glm::vec3(2, 4, 7));
  CHECK(b.center() == glm::vec3(1.5f, 3, 5));
  CHECK(b.half_area() == 1 * 2 + 2 * 4 + 4 * 1);
  CHECK(b.largest_axis() == 2);
  CHECK(b.contains(glm::vec3(2, 2, 3)));
  CHECK(!b.contains(glm::vec3(2.5f, 2, 3)));
  CHECK(b.contains(BBox{}));  // the empty box is inside every box
  // NaN coordinates are ignored by extend; a box of NaN points stays empty.
  BBox n;
  n.extend(glm::vec3(kNaN, 1, kNaN));
  CHECK(n.empty());
  n.extend(glm::vec3(0, 0, 0));
  CHECK(n.lo == glm::vec3(0, 0, 0));
  CHECK(n.hi == glm::vec3(0, 1, 0));
  CHECK(BBox{glm::vec3(kNaN), glm::vec3(kNaN)}.empty());
  // center() does not overflow near FLT_MAX.
  const float big = std::numeric_limits<float>::max();
  CHECK(std::isfinite(BBox{glm::vec3(big), glm::vec3(big)}.center().x));
}

TEST_CASE("bvh: slab test keeps rays on a slab plane with a zero direction component") {
  // Flat box z = 0 over [0,1]^2; rays lying in its plane or on its side planes.
  const BBox flat{glm::vec3(0, 0, 0), glm::vec3(1, 1, 0)};
  float entry = 0.0f;
  for (float zero : {0.0f, -0.0f}) {
    // In the plane z = 0 (lo.z = hi.z = org.z, dir.z = ±0: both z distances NaN).
    const Ray in_plane{{-1, 0.5f, 0}, 0, {1, 0.25f, zero}, kInf};
    CHECK(volley::core::intersect_box(flat, volley::core::make_box_ray(in_plane), kInf, entry));
    CHECK(entry == 1.0f);
    // On the side plane x = 0 (= lo.x), dir.x = ±0; and on x = 1 (= hi.x).
    for (float x : {0.0f, 1.0f}) {
      const Ray down{{x, 0.5f, 2}, 0, {zero, 0, -1}, kInf};
      CHECK(volley::core::intersect_box(flat, volley::core::make_box_ray(down), kInf, entry));
      CHECK(entry == 2.0f);
    }
    // Parallel to the plane but off it: culled.
    const Ray above{{-1, 0.5f, 0.5f}, 0, {1, 0, zero}, kInf};
    CHECK(!volley::core::intersect_box(flat, volley::core::make_box_ray(above), kInf, entry));
    // Next to the box, zero x component, outside the x slab: culled.
    const Ray beside{{1.5f, 0.5f, 2}, 0, {zero, 0, -1}, kInf};
    CHECK(!volley::core::intersect_box(flat, volley::core::make_box_ray(beside), kInf, entry));
  }
}

TEST_CASE("bvh: the padded slab test never misses a box the exact ray touches") {
  // Rays from random origins aimed at points on the edges and corners of random boxes,
  // where entry and exit coincide in exact arithmetic. A double-precision reference
  // (the slab distances of the float inputs, divided, not multiplied by a rounded
  // reciprocal) decides whether the ray touches the box; the padded test must accept
  // every such ray. The unpadded test misses some, which shows the padding is needed
  // and that this test can fail.
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::size_t touching = 0, padded_missed = 0, unpadded_missed = 0;
  for (int i = 0; i < 200000; ++i) {
    const float scale = std::ldexp(1.0f, static_cast<int>(rng() % 16) - 8);
    BBox box;
    box.extend(scale * glm::vec3(unit(rng), unit(rng), unit(rng)));
    box.extend(scale * glm::vec3(unit(rng), unit(rng), unit(rng)));
    // A point on an edge: two coordinates on bounds, one free (or a corner).
    glm::vec3 target;
    const int free_axis = static_cast<int>(rng() % 4);  // 3: a corner
    for (int a = 0; a < 3; ++a)
      target[a] = a == free_axis ? box.lo[a] + unit(rng) * (box.hi[a] - box.lo[a])
                                 : (rng() % 2 ? box.hi[a] : box.lo[a]);
    const glm::vec3 org = target + 3.0f * scale * glm::vec3(unit(rng) - 0.5f, unit(rng) - 0.5f, unit(rng) - 0.5f);
    const Ray ray{org, 0.0f, target - org, kInf};
    double t_enter = 0.0, t_exit = kInf;
    for (int a = 0; a < 3; ++a) {
      const double d = ray.dir[a];
      if (d == 0.0) {
        if (org[a] < box.lo[a] || org[a] > box.hi[a]) t_exit = -1.0;
        continue;
      }
      double t0 = (double(box.lo[a]) - org[a]) / d, t1 = (double(box.hi[a]) - org[a]) / d;
      if (t0 > t1) std::swap(t0, t1);
      t_enter = std::max(t_enter, t0);
      t_exit = std::min(t_exit, t1);
    }
    if (!(t_enter <= t_exit)) continue;
    ++touching;
    const auto r = volley::core::make_box_ray(ray);
    float entry = 0.0f;
    if (!volley::core::intersect_box<true>(box, r, kInf, entry)) ++padded_missed;
    if (!volley::core::intersect_box<false>(box, r, kInf, entry)) ++unpadded_missed;
  }
  MESSAGE("edge/corner rays touching their box: ", touching, ", unpadded test missed ",
          unpadded_missed, ", padded missed ", padded_missed);
  CHECK(touching > 50000);
  CHECK(padded_missed == 0);
  CHECK(unpadded_missed > 0);
}

TEST_CASE("bvh: build invariants on random soups, for several build options") {
  std::mt19937 rng(1);
  for (std::size_t n : {1u, 2u, 3u, 9u, 1000u, 20000u}) {
    const Soup soup = random_soup(n, rng);
    const std::vector<BBox> boxes = soup.boxes();
    for (BvhBuildOptions opt : {BvhBuildOptions{}, BvhBuildOptions{2, 1, 1, 1, 1},
                                BvhBuildOptions{32, 4, 2, 1.0f, 2.0f}, BvhBuildOptions{8, 16, 4, 3.0f, 1.0f}}) {
      CAPTURE(n);
      CAPTURE(opt.bins);
      CAPTURE(opt.max_leaf_size);
      const Bvh bvh = volley::core::build_bvh(boxes, opt);
      check_structure(bvh, boxes, opt);
    }
  }
}

TEST_CASE("bvh: invalid build options are rejected") {
  const std::vector<BBox> boxes(4, BBox{glm::vec3(0), glm::vec3(1)});
  CHECK_THROWS_AS(volley::core::build_bvh(boxes, {1, 8, 1, 1, 1}), std::invalid_argument);
  CHECK_THROWS_AS(volley::core::build_bvh(boxes, {16, 0, 1, 1, 1}), std::invalid_argument);
  CHECK_THROWS_AS(volley::core::build_bvh(boxes, {16, 4, 5, 1, 1}), std::invalid_argument);
  CHECK_THROWS_AS(volley::core::build_bvh(boxes, {16, 4, 1, kNaN, 1}), std::invalid_argument);
}

TEST_CASE("bvh: closest and any hit equal brute force on random triangle soups") {
  std::mt19937 rng(2);
  struct Case {
    std::size_t tris, rays;
    BvhBuildOptions opt;
  };
  for (const Case& c : {Case{1000, 3000, {}}, Case{10000, 600, {}}, Case{10000, 300, {2, 1, 1, 1, 1}},
                        Case{10000, 300, {32, 16, 4, 1, 1}}, Case{50000, 200, {}}}) {
    CAPTURE(c.tris);
    CAPTURE(c.opt.max_leaf_size);
    const Soup soup = random_soup(c.tris, rng);
    const std::vector<BBox> boxes = soup.boxes();
    const Bvh bvh = volley::core::build_bvh(boxes, c.opt);
    check_structure(bvh, boxes, c.opt);
    const std::vector<Ray> rays = random_rays(bounds_of(boxes), c.rays, rng);
    // Traversal hands every primitive whose box the ray touches to the leaf callback,
    // also for rays aimed exactly at box edges and corners (where an unpadded slab
    // test skips boxes, see above).
    std::vector<Ray> edge_rays = rays;
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    for (std::size_t i = 0; i < c.rays; ++i) {
      const BBox& b = boxes[rng() % boxes.size()];
      glm::vec3 target;
      const int free_axis = static_cast<int>(rng() % 4);  // 3: a corner
      for (int a = 0; a < 3; ++a)
        target[a] = a == free_axis ? b.lo[a] + unit(rng) * (b.hi[a] - b.lo[a])
                                   : (rng() % 2 ? b.hi[a] : b.lo[a]);
      edge_rays.push_back({rays[i].org, 0, target - rays[i].org, kInf});
    }
    std::size_t touched = 0;
    CHECK(count_skipped_boxes(bvh, boxes, edge_rays, touched) == 0);
    const Agreement g = compare_with_brute_force(bvh, soup, rays);
    CHECK(g.hits > c.rays / 4);  // the generator really makes both
    CHECK(g.misses > c.rays / 20);
    CHECK(g.closest_wrong == 0);
    CHECK(g.any_wrong == 0);
  }
}

TEST_CASE("bvh: axis-aligned rays with origins on slab planes of flat boxes (stress item 4)") {
  // Rays in the slab planes of many leaf boxes, through shared edges and vertices.
  Soup soup;
  const std::vector<Ray> rays = volley::test::slab_plane_grid<Ray>(16, soup, [](glm::vec3 o, glm::vec3 d) {
    return Ray{o, 0, d, kInf};
  });
  const std::vector<BBox> boxes = soup.boxes();
  for (BvhBuildOptions opt : {BvhBuildOptions{}, BvhBuildOptions{16, 1, 1, 1, 1}}) {
    const Bvh bvh = volley::core::build_bvh(boxes, opt);
    check_structure(bvh, boxes, opt);
    std::size_t touched = 0;
    CHECK(count_skipped_boxes(bvh, boxes, rays, touched) == 0);
    CHECK(touched > rays.size());
    for (auto test : {volley::TriangleTest::plane, volley::TriangleTest::moller,
                      volley::TriangleTest::watertight}) {
      CAPTURE(volley::to_string(test));
      CAPTURE(opt.max_leaf_size);
      soup.test = test;
      const Agreement g = compare_with_brute_force(bvh, soup, rays);
      MESSAGE("grid, ", volley::to_string(test), ": ", g.rays, " rays, ", g.hits, " hits, ",
              g.tie_prims, " ties at equal t");
      CHECK(g.hits > g.rays / 2);
      CHECK(g.misses > 0);
      CHECK(g.closest_wrong == 0);
      CHECK(g.any_wrong == 0);
    }
  }
}

TEST_CASE("bvh: degenerate inputs build, stay within bounds and agree with brute force") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> pos(-1.0f, 1.0f);
  auto rand3 = [&] { return glm::vec3(pos(rng), pos(rng), pos(rng)); };

  SUBCASE("all identical triangles") {
    Soup soup;
    for (int i = 0; i < 5000; ++i) soup.add({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
    const auto boxes = soup.boxes();
    const Bvh bvh = volley::core::build_bvh(boxes);
    check_structure(bvh, boxes, {});
    std::vector<Ray> rays;
    for (int i = 0; i < 50; ++i) rays.push_back({glm::vec3(0.3f, 0.2f, 1) + 0.1f * rand3(), 0, {0, 0, -1}, kInf});
    rays.push_back({{2, 2, 1}, 0, {0, 0, -1}, kInf});
    const Agreement g = compare_with_brute_force(bvh, soup, rays);
    CHECK(g.hits == 50);
    CHECK(g.closest_wrong == 0);
    CHECK(g.any_wrong == 0);
  }
  SUBCASE("zero-area triangles (repeated vertices, collinear, points) among regular ones") {
    Soup soup;
    for (int i = 0; i < 3000; ++i) {
      const glm::vec3 p = rand3(), q = rand3();
      switch (i % 4) {
        case 0: soup.add(p, p, q); break;                          // repeated vertex
        case 1: soup.add(p, 0.5f * p + 0.5f * q, q); break;        // collinear
        case 2: soup.add(p, p, p); break;                          // a point
        default: soup.add(p, p + 0.1f * rand3(), p + 0.1f * rand3()); break;
      }
    }
    check_random_rays(soup, rng);
  }
  SUBCASE("many coincident centroids (nested triangles of every size)") {
    Soup soup;
    for (int i = 0; i < 4000; ++i) {
      const float s = 0.001f + 0.001f * static_cast<float>(i % 997);
      const glm::vec3 a = s * rand3(), b = s * rand3();
      soup.add(a, b, -a - b);  // centroid exactly 0 up to rounding: boxes differ, centres coincide or nearly
    }
    for (int i = 0; i < 2000; ++i) {
      const glm::vec3 c = glm::vec3(0.5f, 0.5f, 0.5f);
      const float s = 0.01f * static_cast<float>(1 + i % 50);
      soup.add(c + glm::vec3(-s, -s, 0), c + glm::vec3(s, -s, 0), c + glm::vec3(0, s, 0) + glm::vec3(0, 0, 0.0f));
    }
    check_random_rays(soup, rng);
  }
  SUBCASE("NaN and Inf vertices (empty and infinite boxes) among regular triangles") {
    Soup soup = random_soup(2000, rng);
    for (int i = 0; i < 300; ++i) {
      const glm::vec3 p = rand3();
      switch (i % 5) {
        case 0: soup.add(glm::vec3(kNaN), glm::vec3(kNaN), glm::vec3(kNaN)); break;  // empty box
        case 1: soup.add(p, glm::vec3(kNaN, 0, 0), p + 0.1f); break;
        case 2: soup.add(p, glm::vec3(kInf, 0, 0), p + 0.1f); break;
        case 3: soup.add(glm::vec3(-kInf), glm::vec3(kInf), p); break;
        default: soup.add(p, p + glm::vec3(0.1f, 0, 0), glm::vec3(p.x, p.y, kNaN)); break;
      }
    }
    const auto boxes = soup.boxes();
    const Bvh bvh = volley::core::build_bvh(boxes);
    check_structure(bvh, boxes, {});
    BBox finite;
    for (std::size_t i = 0; i < 2000; ++i) finite.extend(boxes[i]);
    const std::vector<Ray> rays = random_rays(finite, 1000, rng);
    std::size_t touched = 0;
    CHECK(count_skipped_boxes(bvh, boxes, rays, touched) == 0);
    const Agreement g = compare_with_brute_force(bvh, soup, rays);
    CHECK(g.hits > 0);
    CHECK(g.closest_wrong == 0);
    CHECK(g.any_wrong == 0);
  }
  SUBCASE("coordinates near +-FLT_MAX (extents and areas overflow to inf)") {
    // Centroid extents of 6e38 overflow: such an axis cannot be binned, and its
    // (centroid - min) * 0 is NaN: it must still map to a valid bin.
    Soup soup;
    const float big = 3e38f;
    for (int i = 0; i < 2000; ++i) {
      const glm::vec3 p = big * rand3();
      const glm::vec3 q = glm::vec3(p.x, 0.5f * p.y, 0.25f * p.z);
      soup.add(q, q + glm::vec3(0, 0, 1e37f), q + glm::vec3(0, 1e37f, 0));
    }
    const auto boxes = soup.boxes();
    const Bvh bvh = volley::core::build_bvh(boxes);
    check_structure(bvh, boxes, {});
    std::vector<Ray> rays;
    for (int i = 0; i < 200; ++i) {
      const glm::vec3 q = soup.v[3 * (i * 7)] + glm::vec3(0, 1e36f, 1e36f);
      rays.push_back({glm::vec3(-big, q.y, q.z), 0, {1, 0, 0}, kInf});
    }
    // The triangle tests overflow at this scale (normals of 1e37-long edges), so the
    // traversal is checked against the boxes themselves.
    std::size_t touched = 0;
    CHECK(count_skipped_boxes(bvh, boxes, rays, touched) == 0);
    CHECK(touched >= rays.size());
    const Agreement g = compare_with_brute_force(bvh, soup, rays);
    CHECK(g.closest_wrong == 0);
    CHECK(g.any_wrong == 0);
  }
  SUBCASE("geometrically spaced boxes over the whole float range (depth guard)") {
    // Centroids 2^(k/8) from 2^-140 to 2^120: binned SAH keeps splitting off the top
    // bins, a chain far deeper than kBvhMaxDepth without the depth guard. (Below about
    // 2^-60 Moller's determinant underflows to 0, so those triangles are never hit.)
    Soup soup;
    for (int k = -8 * 140; k < 8 * 120; ++k) {
      const float x = std::exp2(static_cast<float>(k) / 8.0f);
      const glm::vec3 p(x, x, x);
      soup.add(p, p + glm::vec3(0.01f * x, 0, 0), p + glm::vec3(0, 0.01f * x, 0));
    }
    const auto boxes = soup.boxes();
    const Bvh bvh = volley::core::build_bvh(boxes);
    check_structure(bvh, boxes, {});
    MESSAGE("geometric spacing: depth ", volley::core::bvh_stats(bvh).depth);
    std::vector<Ray> rays;
    for (int k = -8 * 140 + 3; k < 8 * 120; k += 37) {
      const float x = std::exp2(static_cast<float>(k) / 8.0f);
      rays.push_back({{x * 1.001f, x * 1.001f, -1.0f}, 0, {0, 0, 1}, kInf});
    }
    const Agreement g = compare_with_brute_force(bvh, soup, rays);
    CHECK(g.hits > rays.size() / 3);
    CHECK(g.closest_wrong == 0);
    CHECK(g.any_wrong == 0);
  }
}

TEST_CASE("bvh: empty, single-primitive and non-finite rays") {
  const Soup one = [] {
    Soup s;
    s.add({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
    return s;
  }();
  std::size_t calls = 0;
  auto count_calls = [&](std::uint32_t, float&) {
    ++calls;
    return true;
  };
  const Ray down{{0.25f, 0.25f, 1}, 0, {0, 0, -1}, kInf};

  const Bvh empty = volley::core::build_bvh({});
  CHECK(empty.nodes.empty());
  CHECK(!volley::core::traverse<false>(empty, down, count_calls));
  CHECK(calls == 0);
  CHECK(volley::core::bvh_stats(empty).nodes == 0);

  const Bvh bvh = volley::core::build_bvh(one.boxes());
  check_structure(bvh, one.boxes(), {});
  CHECK(bvh_closest(bvh, one, down).t == 1.0f);
  CHECK(volley::core::bvh_stats(bvh).sah_cost == 1.0);

  // Non-finite rays: no hit and no leaf call, whatever is NaN or infinite.
  std::vector<Ray> bad;
  for (float x : {kNaN, kInf, -kInf}) {
    bad.push_back({{x, 0.25f, 1}, 0, {0, 0, -1}, kInf});
    bad.push_back({{0.25f, 0.25f, x}, 0, {0, 0, -1}, kInf});
    bad.push_back({{0.25f, 0.25f, 1}, 0, {0, 0, x}, kInf});
    bad.push_back({{0.25f, 0.25f, 1}, 0, {x, 0, -1}, kInf});
  }
  bad.push_back({{0.25f, 0.25f, 1}, kNaN, {0, 0, -1}, kInf});
  bad.push_back({{0.25f, 0.25f, 1}, 0, {0, 0, -1}, kNaN});
  for (const Ray& r : bad) {
    CAPTURE(describe(r));
    calls = 0;
    CHECK(!volley::core::traverse<false>(bvh, r, count_calls));
    CHECK(!volley::core::traverse<true>(bvh, r, count_calls));
    CHECK(calls == 0);
  }
  // tmin > tmax, a zero direction, tmax at the hit: no hit, terminates.
  CHECK(!bvh_closest(bvh, one, {{0.25f, 0.25f, 1}, 2, {0, 0, -1}, 1}).hit);
  CHECK(!bvh_closest(bvh, one, {{0.25f, 0.25f, 0}, 0, {0, 0, 0}, kInf}).hit);
  CHECK(!bvh_closest(bvh, one, {{0.25f, 0.25f, 1}, 0, {0, 0, -1}, 1.0f}).hit);
  CHECK(bvh_closest(bvh, one, {{0.25f, 0.25f, 1}, 1.0f, {0, 0, -1}, 1.5f}).hit);
}

TEST_CASE("bvh: one million primitives, random and all identical, build without trouble") {
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> pos(0.0f, 100.0f);
  std::uniform_real_distribution<float> size(0.0f, 0.2f);
  constexpr std::size_t n = 1000000;
  std::vector<BBox> boxes(n);
  for (BBox& b : boxes) {
    b.lo = glm::vec3(pos(rng), pos(rng), pos(rng));
    b.hi = b.lo + glm::vec3(size(rng), size(rng), size(rng));
  }
  auto t0 = std::chrono::steady_clock::now();
  const Bvh bvh = volley::core::build_bvh(boxes);
  const double secs = seconds_since(t0);
  const auto stats = volley::core::bvh_stats(bvh);
  MESSAGE("1M random boxes: build ", secs, " s = ", 1e-6 * n / secs, " M prims/s, SAH cost ",
          stats.sah_cost, ", depth ", stats.depth, ", mean leaf ", stats.mean_leaf_size);
  check_structure(bvh, boxes, {});

  const std::vector<BBox> same(n, BBox{glm::vec3(1, 2, 3), glm::vec3(2, 3, 4)});
  t0 = std::chrono::steady_clock::now();
  const Bvh flat = volley::core::build_bvh(same);
  MESSAGE("1M identical boxes: build ", seconds_since(t0), " s");
  check_structure(flat, same, {});
  std::size_t calls = 0;
  const Ray ray{{1.5f, 2.5f, 0}, 0, {0, 0, 1}, kInf};
  CHECK(!volley::core::traverse<false>(flat, ray, [&](std::uint32_t, float&) {
    ++calls;
    return false;
  }));
  CHECK(calls == n);  // every leaf visited, none skipped, the stack never overflows
}

TEST_CASE("bvh: shared meshes (bunny, teapot) against brute force") {
  for (const std::string name : {"stanford-bunny.obj", "teapot.obj"}) {
    const std::string path = VOLLEY_SHARED_SCENES "/" + name;
    Soup soup = read_obj(path);
    soup.test = volley::TriangleTest::watertight;
    if (soup.size() == 0) {
      MESSAGE("skipped: ", path, " not found");
      continue;
    }
    CAPTURE(name);
    const auto boxes = soup.boxes();
    const auto t0 = std::chrono::steady_clock::now();
    const Bvh bvh = volley::core::build_bvh(boxes);
    const double secs = seconds_since(t0);
    const auto stats = volley::core::bvh_stats(bvh);
    MESSAGE(name, ": ", soup.size(), " tris, build ", 1e3 * secs, " ms = ",
            1e-6 * soup.size() / secs, " M prims/s, SAH cost ", stats.sah_cost, ", depth ",
            stats.depth, ", ", stats.nodes, " nodes, mean leaf ", stats.mean_leaf_size);
    check_structure(bvh, boxes, {});

    // Rays aimed at random triangle centroids from outside (hits), from inside the
    // bounds in random directions, and random rays (misses).
    std::mt19937 rng(5);
    const BBox bounds = bounds_of(boxes);
    std::vector<Ray> rays = random_rays(bounds, 300, rng);
    std::uniform_int_distribution<std::uint32_t> pick(0, static_cast<std::uint32_t>(soup.size() - 1));
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    for (int i = 0; i < 300; ++i) {
      const std::uint32_t p = pick(rng);
      const glm::vec3 target = (soup.v[3 * p] + soup.v[3 * p + 1] + soup.v[3 * p + 2]) / 3.0f;
      const glm::vec3 org = bounds.center() + 2.0f * glm::length(bounds.diagonal()) *
                                                  glm::normalize(glm::vec3(unit(rng), unit(rng), unit(rng)));
      rays.push_back({org, 0, target - org, kInf});
    }
    const Agreement g = compare_with_brute_force(bvh, soup, rays);
    MESSAGE(name, ": ", g.rays, " rays, ", g.hits, " hits, ", g.tie_prims, " ties at equal t");
    CHECK(g.hits > 300);
    CHECK(g.misses > 25);
    CHECK(g.closest_wrong == 0);
    CHECK(g.any_wrong == 0);
  }
}
