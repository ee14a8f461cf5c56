// Scalar polygon oracle (core/polygon.h): validation, the even-odd test against an ear
// triangulation built here, the boundary rule at vertices and shared edges, and bounds.
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <regex>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "common/bad_rays.h"
#include "core/polygon.h"
#include "core/triangle_moller.h"

namespace {

using namespace volley::core;
using Vec3f = Vec3<float>;
using Vec3d = Vec3<double>;
using Vec2d = glm::dvec2;

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// ---- 2D shapes and their ear triangulation ----------------------------------------------------

struct Shape {
  const char* name;
  std::vector<Vec2d> outline;
};

std::vector<Shape> shapes() {
  std::vector<Shape> out;
  out.push_back({"square", {{0, 0}, {2, 0}, {2, 2}, {0, 2}}});
  Shape hexagon{"hexagon", {}};
  for (int i = 0; i < 6; ++i)
    hexagon.outline.push_back({1.5 * std::cos(i * std::numbers::pi / 3), 1.5 * std::sin(i * std::numbers::pi / 3)});
  out.push_back(hexagon);
  out.push_back({"L", {{0, 0}, {3, 0}, {3, 1}, {1, 1}, {1, 3}, {0, 3}}});
  Shape star{"star", {}};
  for (int i = 0; i < 10; ++i) {
    const double r = i % 2 ? 0.8 : 2.0, a = std::numbers::pi / 2 + i * std::numbers::pi / 5;
    star.outline.push_back({r * std::cos(a), r * std::sin(a)});
  }
  out.push_back(star);
  // A comb: a base 4.5 x 1 with five teeth 0.5 wide and 2 tall.
  Shape comb{"comb", {{0, 0}, {4.5, 0}}};
  for (int i = 4; i >= 0; --i) {
    comb.outline.push_back({i + 0.5, 3});
    comb.outline.push_back({double(i), 3});
    if (i > 0) {
      comb.outline.push_back({double(i), 1});
      comb.outline.push_back({i - 0.5, 1});
    }
  }
  out.push_back(comb);
  // The same comb, clockwise: orientation must not matter.
  Shape cw{"comb, clockwise", comb.outline};
  std::reverse(cw.outline.begin(), cw.outline.end());
  out.push_back(cw);
  return out;
}

double cross2(Vec2d a, Vec2d b, Vec2d c) { return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x); }

bool in_triangle_2d(Vec2d p, Vec2d a, Vec2d b, Vec2d c) {  // closed, either orientation
  const double d1 = cross2(a, b, p), d2 = cross2(b, c, p), d3 = cross2(c, a, p);
  return (d1 >= 0 && d2 >= 0 && d3 >= 0) || (d1 <= 0 && d2 <= 0 && d3 <= 0);
}

// Ear clipping (Meisters 1975), O(n^3): fine for a few dozen vertices. Index triples.
std::vector<std::array<int, 3>> ear_triangulate(const std::vector<Vec2d>& poly) {
  double area = 0;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++)
    area += poly[j].x * poly[i].y - poly[i].x * poly[j].y;
  std::vector<int> idx(poly.size());
  for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = int(i);
  if (area < 0) std::reverse(idx.begin(), idx.end());
  std::vector<std::array<int, 3>> tris;
  while (idx.size() > 3) {
    bool clipped = false;
    for (std::size_t i = 0; i < idx.size() && !clipped; ++i) {
      const int a = idx[(i + idx.size() - 1) % idx.size()], b = idx[i], c = idx[(i + 1) % idx.size()];
      if (cross2(poly[a], poly[b], poly[c]) <= 0) continue;  // reflex
      bool empty = true;
      for (int o : idx)
        if (o != a && o != b && o != c && in_triangle_2d(poly[o], poly[a], poly[b], poly[c])) empty = false;
      if (!empty) continue;
      tris.push_back({a, b, c});
      idx.erase(idx.begin() + std::ptrdiff_t(i));
      clipped = true;
    }
    REQUIRE(clipped);
  }
  tris.push_back({idx[0], idx[1], idx[2]});
  return tris;
}

bool inside_2d(const std::vector<Vec2d>& poly, const std::vector<std::array<int, 3>>& tris, Vec2d p) {
  for (const auto& t : tris)
    if (in_triangle_2d(p, poly[t[0]], poly[t[1]], poly[t[2]])) return true;
  return false;
}

double distance_to_segment(Vec3d p, Vec3d a, Vec3d b) {
  const Vec3d ab = b - a;
  const double s = std::clamp(glm::dot(p - a, ab) / glm::dot(ab, ab), 0.0, 1.0);
  return glm::length(p - (a + s * ab));
}

// A random rotation (uniform quaternion).
glm::dmat3 random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> g;
  const glm::dquat q = glm::normalize(glm::dquat(g(rng), g(rng), g(rng), g(rng)));
  return glm::mat3_cast(q);
}

// A polygon embedded in 3D: outline scaled, rotated and moved, rounded to float.
struct Placed {
  Polygon poly;
  std::vector<Vec2d> outline;              // the 2D outline
  std::vector<std::array<int, 3>> tris;    // its ear triangulation
  glm::dmat3 rot;                          // 2D (x, y, 0) -> 3D
  Vec3d offset;
};

Placed place(const Shape& shape, const glm::dmat3& rot, Vec3d offset) {
  std::vector<glm::vec3> verts;
  for (Vec2d p : shape.outline) verts.push_back(glm::vec3(rot * Vec3d(p, 0) + offset));
  return {make_polygon(verts), shape.outline, ear_triangulate(shape.outline), rot, offset};
}

// ---- random rays against the triangulation ----------------------------------------------------

TEST_CASE_TEMPLATE("polygon: even-odd test agrees with an ear triangulation away from the boundary",
                   T, float, double) {
  constexpr double kBand = 1e-5;  // disagreement allowed this close to the boundary
  std::mt19937 rng(2718);
  for (const Shape& shape : shapes()) {
    const std::string shape_name = shape.name;
    CAPTURE(shape_name);
    Vec2d lo(1e9), hi(-1e9);
    for (Vec2d p : shape.outline) lo = glm::min(lo, p), hi = glm::max(hi, p);
    int inside = 0, outside = 0, far_disagree = 0, near_disagree = 0;
    double t_err = 0;
    for (int placement = 0; placement < 4; ++placement) {
      const glm::dmat3 rot = placement == 0 ? glm::dmat3(1) : random_rotation(rng);
      const Vec3d offset = placement == 0 ? Vec3d(0) : Vec3d(std::uniform_real_distribution<double>(-8, 8)(rng));
      const Placed pl = place(shape, rot, offset);
      for (int s = 0; s < 5000; ++s) {
        std::uniform_real_distribution<double> ux(lo.x - 0.1 * (hi.x - lo.x), hi.x + 0.1 * (hi.x - lo.x));
        std::uniform_real_distribution<double> uy(lo.y - 0.1 * (hi.y - lo.y), hi.y + 0.1 * (hi.y - lo.y));
        std::uniform_real_distribution<double> h(1, 5), side(-1, 1);
        const Vec3d target = rot * Vec3d(ux(rng), uy(rng), 0) + offset;
        const Vec3d from = rot * Vec3d(ux(rng), uy(rng), side(rng) < 0 ? -h(rng) : h(rng)) + offset;
        const RayT<float> rf{Vec3f(from), 0.0f, Vec3f(target - from), kInf};
        const RayT<T> ray = volley::core::ray_cast<T>(rf);

        // Reference: any triangle of the triangulation, float vertices, in double.
        bool ref = false;
        double ref_t = 0;
        for (const auto& tri : pl.tris) {
          TriHit<double> hd{};
          if (intersect_moller(volley::core::ray_cast<double>(rf), Vec3d(pl.poly.vertices[tri[0]]),
                               Vec3d(pl.poly.vertices[tri[1]]), Vec3d(pl.poly.vertices[tri[2]]), hd)) {
            ref = true;
            ref_t = hd.t;
          }
        }
        // Distance of the ray's plane point to the outline, for the tolerance band.
        const Vec3d n(pl.poly.normal);
        const Vec3d org(rf.org), dir(rf.dir);
        const Vec3d q = org + (double(pl.poly.d) - glm::dot(n, org)) / glm::dot(n, dir) * dir;
        double dist = 1e9;
        for (std::size_t i = 0, j = pl.poly.vertices.size() - 1; i < pl.poly.vertices.size(); j = i++)
          dist = std::min(dist, distance_to_segment(q, Vec3d(pl.poly.vertices[j]), Vec3d(pl.poly.vertices[i])));

        T t = -7;
        const bool hit = intersect_polygon(ray, pl.poly, t);
        (ref ? inside : outside)++;
        if (hit != ref) (dist < kBand ? near_disagree : far_disagree)++;
        if (hit && ref) t_err = std::max(t_err, std::abs(double(t) - ref_t) / ref_t);
        if (!hit) CHECK(t == -7);
      }
    }
    CHECK(inside > 2000);   // > 10% of 20000 rays
    CHECK(outside > 2000);
    CHECK(far_disagree == 0);
    CHECK(t_err < 1e-5);
    MESSAGE(shape_name << ": " << inside << " in, " << outside << " out, " << near_disagree
                       << " disagreements within " << kBand << " of the boundary, max t rel. error "
                       << t_err);
  }
}

// ---- boundary rule -----------------------------------------------------------------------------

// Vertical ray down onto the z = 0 plane at (x, y): exact hit point for float coordinates.
template <class T>
bool hit_at(const Polygon& poly, double x, double y) {
  const RayT<T> ray{Vec3<T>(T(x), T(y), 5), 0, Vec3<T>(0, 0, -1), std::numeric_limits<T>::infinity()};
  T t = 0;
  const bool hit = intersect_polygon(ray, poly, t);
  if (hit) CHECK(t == 5);
  return hit;
}

TEST_CASE_TEMPLATE("polygon: rays exactly through vertices and edge points follow the boundary rule",
                   T, float, double) {
  int checked = 0, vertex_line_checked = 0;
  for (const Shape& shape : shapes()) {
    const std::string shape_name = shape.name;
    CAPTURE(shape_name);
    const Placed pl = place(shape, glm::dmat3(1), Vec3d(0));
    REQUIRE(pl.poly.drop_axis == 2);
    const auto& v = pl.poly.vertices;
    const std::size_t count = v.size();
    // Float outline (exactly what the polygon holds) for the reference.
    std::vector<Vec2d> outline;
    for (const Vec3f& p : v) outline.push_back(Vec2d(p.x, p.y));
    // Points exactly on the boundary: vertices (any shape) and edge midpoints (dyadic shapes,
    // where the midpoint is exact). Rule: inside iff the point moved by (+e, +e^2) is.
    const bool dyadic = std::string(shape.name) != "hexagon" && std::string(shape.name) != "star";
    for (std::size_t i = 0; i < count; ++i) {
      std::vector<Vec2d> points = {outline[i]};
      if (dyadic) points.push_back(0.5 * (outline[i] + outline[(i + 1) % count]));
      for (Vec2d p : points) {
        const bool want = inside_2d(outline, pl.tris, p + Vec2d(1e-4, 1e-8));
        CAPTURE(p.x);
        CAPTURE(p.y);
        CHECK(hit_at<T>(pl.poly, p.x, p.y) == want);
        ++checked;
      }
      // Interior or exterior points whose in-plane +u ray passes exactly through vertex i.
      for (double back : {0.375, 0.125, 2.5}) {
        const Vec2d p(double(float(outline[i].x - back)), outline[i].y);
        double dist = 1e9;
        for (std::size_t a = 0, b = count - 1; a < count; b = a++)
          dist = std::min(dist, distance_to_segment(Vec3d(p, 0), Vec3d(outline[b], 0), Vec3d(outline[a], 0)));
        if (dist < 1e-3) continue;  // on the boundary: covered above
        CAPTURE(p.x);
        CAPTURE(p.y);
        CHECK(hit_at<T>(pl.poly, p.x, p.y) == inside_2d(outline, pl.tris, p));
        ++vertex_line_checked;
      }
    }
  }
  CHECK(checked > 60);
  CHECK(vertex_line_checked > 60);

  // A diamond: from its centre the +u ray leaves exactly through the vertex (1, 0); from the
  // left the ray passes exactly through both side vertices. A count that takes a vertex twice
  // (or not at all) gets these wrong.
  const Polygon diamond = make_polygon({{0, -1, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}});
  CHECK(hit_at<T>(diamond, 0, 0));
  CHECK(hit_at<T>(diamond, 0.5, 0));
  CHECK(hit_at<T>(diamond, -0.5, 0));
  CHECK_FALSE(hit_at<T>(diamond, -2, 0));
  CHECK_FALSE(hit_at<T>(diamond, 2, 0));
  // The top vertex is a local maximum: a 2D ray through it must not toggle.
  CHECK_FALSE(hit_at<T>(diamond, -0.5, 1));
}

// Polygons tiling a region claim every interior shared vertex and edge point exactly once.
TEST_CASE_TEMPLATE("polygon: tiles claim shared vertices and edge points exactly once", T, float, double) {
  std::vector<std::vector<glm::vec3>> tiles;
  // A 2 x 2 grid of quads with the centre vertex moved to (0.5, 0.25).
  const glm::vec3 c(0.5f, 0.25f, 0);
  tiles.push_back({{-2, -2, 0}, {0, -2, 0}, c, {-2, 0, 0}});
  tiles.push_back({{0, -2, 0}, {2, -2, 0}, {2, 0, 0}, c});
  tiles.push_back({c, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}});
  tiles.push_back({{-2, 0, 0}, c, {0, 2, 0}, {-2, 2, 0}});
  // A fan of 8 triangles around (5, 0.5) on a dyadic ring (some clockwise).
  const glm::vec3 hub(5, 0.5f, 0);
  const glm::vec3 ring[8] = {{7, 0, 0}, {7, 2, 0}, {5, 3, 0}, {3.5f, 2.5f, 0},
                             {3, 0.5f, 0}, {3.25f, -1.5f, 0}, {5, -2, 0}, {6.5f, -1.75f, 0}};
  for (int i = 0; i < 8; ++i) {
    if (i % 2)
      tiles.push_back({hub, ring[i], ring[(i + 1) % 8]});
    else
      tiles.push_back({ring[(i + 1) % 8], ring[i], hub});
  }
  std::vector<Polygon> polys;
  for (const auto& t : tiles) polys.push_back(make_polygon(t));

  std::vector<glm::vec3> interior = {c, 0.5f * (c + glm::vec3(0, -2, 0)), 0.5f * (c + glm::vec3(2, 0, 0)),
                                     0.5f * (c + glm::vec3(0, 2, 0)), 0.5f * (c + glm::vec3(-2, 0, 0)),
                                     0.25f * c + 0.75f * glm::vec3(2, 0, 0), hub};
  for (const glm::vec3& r : ring) {
    interior.push_back(0.5f * (hub + r));
    interior.push_back(0.125f * hub + 0.875f * r);
  }
  for (const glm::vec3& p : interior) {
    CAPTURE(p.x);
    CAPTURE(p.y);
    int claims = 0;
    for (const Polygon& poly : polys) claims += hit_at<T>(poly, p.x, p.y);
    CHECK(claims == 1);
  }
}

// ---- validation ----------------------------------------------------------------------------------

std::string error_of(std::vector<glm::vec3> verts) {
  try {
    make_polygon(std::move(verts));
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

std::vector<double> numbers_in(const std::string& text) {
  std::vector<double> out;
  const std::regex number(R"([-+]?[0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), number); it != std::sregex_iterator(); ++it)
    out.push_back(std::stod(it->str()));
  return out;
}

bool mentions(const std::vector<double>& numbers, double value) {
  return std::any_of(numbers.begin(), numbers.end(),
                     [&](double x) { return std::abs(x - value) <= 1e-3 * std::abs(value); });
}

TEST_CASE("polygon: make_polygon rejects bad input with a clear message") {
  const std::string few = error_of({{0, 0, 0}, {1, 0, 0}});
  CHECK(few.find("at least 3 vertices") != std::string::npos);
  CHECK(few.find("got 2") != std::string::npos);
  CHECK(error_of({}).find("at least 3") != std::string::npos);
  CHECK(error_of({{0, 0, 0}, {1, kNaN, 0}, {0, 1, 0}}).find("non-finite") != std::string::npos);
  CHECK(error_of({{0, 0, 0}, {1, 0, 0}, {0, kInf, 0}}).find("non-finite") != std::string::npos);
  CHECK(error_of({{1, 1, 1}, {1, 1, 1}, {1, 1, 1}}).find("zero area") != std::string::npos);
  CHECK(error_of({{0, 0, 0}, {1, 2, 3}, {2, 4, 6}, {0.5f, 1, 1.5f}}).find("zero area") != std::string::npos);

  // Non-planar: lift one corner of a 2 x 2 square. The message states the measured distance
  // and the tolerance; both are recomputed here (Newell normal through the centroid).
  const float lift = 0.01f;
  const std::vector<glm::vec3> quad = {{0, 0, 0}, {2, 0, 0}, {2, 2, lift}, {0, 2, 0}};
  const std::string msg = error_of(quad);
  CAPTURE(msg);
  REQUIRE(msg.find("not coplanar") != std::string::npos);
  Vec3d centroid(0), newell(0);
  for (const glm::vec3& p : quad) centroid += Vec3d(p) / 4.0;
  for (std::size_t i = 0; i < 4; ++i) {
    const Vec3d a(quad[i]), b(quad[(i + 1) % 4]);
    newell += glm::cross(a - centroid, b - centroid);  // = Newell's sums for a closed loop
  }
  const Vec3d n = glm::normalize(newell);
  double deviation = 0;
  for (const glm::vec3& p : quad) deviation = std::max(deviation, std::abs(glm::dot(n, Vec3d(p) - centroid)));
  const double tolerance = 1e-4 * std::sqrt(8.0 + double(lift) * lift);
  const std::vector<double> numbers = numbers_in(msg);
  CHECK(deviation > tolerance);
  CHECK(mentions(numbers, deviation));
  CHECK(mentions(numbers, tolerance));

  // Within the tolerance it is accepted, and the deviation is kept for the bounds.
  const Polygon ok = make_polygon({{0, 0, 0}, {2, 0, 0}, {2, 2, 1e-5f}, {0, 2, 0}});
  CHECK(ok.plane_deviation > 0);
  CHECK(ok.plane_deviation < 1e-5f);
}

TEST_CASE("polygon: bounds hold every vertex and every hit point") {
  std::mt19937 rng(31);
  // Nearly planar (lifted corner within tolerance), tilted and moved.
  std::vector<glm::vec3> verts = {{0, 0, 0}, {2, 0, 0}, {2, 2, 2e-4f}, {1, 0.5f, 0}, {0, 2, 0}};
  const glm::dmat3 rot = random_rotation(rng);
  for (glm::vec3& p : verts) p = glm::vec3(rot * Vec3d(p) + Vec3d(3, -1, 2));
  const Polygon poly = make_polygon(verts);
  const Vec3f lo = volley::core::polygon_lo(poly), hi = volley::core::polygon_hi(poly);
  for (const Vec3f& p : poly.vertices) CHECK((glm::all(glm::lessThanEqual(lo, p)) && glm::all(glm::lessThanEqual(p, hi))));
  int hits = 0;
  std::uniform_real_distribution<double> u(-0.5, 2.5);
  for (int s = 0; s < 20000; ++s) {
    const Vec3d target = rot * Vec3d(u(rng), u(rng), 0) + Vec3d(3, -1, 2);
    const Vec3d from = target + 4.0 * glm::normalize(Vec3d(u(rng) - 1, u(rng) - 1, 1.5));
    const RayT<double> ray{from, 0, target - from, std::numeric_limits<double>::infinity()};
    double t = 0;
    if (!intersect_polygon(ray, poly, t)) continue;
    ++hits;
    const Vec3d q = ray.org + t * ray.dir;
    CHECK((glm::all(glm::lessThanEqual(Vec3d(lo), q)) && glm::all(glm::lessThanEqual(q, Vec3d(hi)))));
  }
  CHECK(hits > 2000);
}

TEST_CASE_TEMPLATE("polygon: bad rays and the half-open range", T, float, double) {
  const Polygon square = make_polygon({{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}});
  const RayT<T> good{Vec3<T>(0.25, 0.5, 0), 0, Vec3<T>(0, 0, 1), T(1)};
  T t = -7;
  CHECK_FALSE(intersect_polygon(good, square, t));  // t == tmax exactly
  RayT<T> r = good;
  r.tmax = std::nextafter(T(1), T(2));
  REQUIRE(intersect_polygon(r, square, t));
  CHECK(t == 1);
  r.tmin = 1;
  CHECK(intersect_polygon(r, square, t));
  const T nan = std::numeric_limits<T>::quiet_NaN();
  std::vector<RayT<T>> bad = volley::test::non_finite_variants(r);
  RayT<T> b = r;
  b.dir = Vec3<T>(0);
  bad.push_back(b);
  b = r;
  b.tmin = 2;
  b.tmax = 0.5;
  bad.push_back(b);
  b = r;
  b.tmax = nan;
  bad.push_back(b);
  for (const RayT<T>& ray : bad) {
    t = -7;
    CHECK_FALSE(intersect_polygon(ray, square, t));
    CHECK(t == -7);
  }
}

}  // namespace
