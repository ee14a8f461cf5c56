#include "capi_case.h"

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <limits>

namespace fuzz_capi {

Case current;

namespace {

void print_case(std::size_t ray) {
  std::fprintf(stderr, "commit: test %d isa %d robust %d reference_double %d\n", current.test, current.isa,
               current.robust, current.reference_double);
  if (current.geometry) {
    const Geometry& g = *current.geometry;
    for (std::size_t i = 0; i + 2 < g.xyz.size(); i += 3)
      std::fprintf(stderr, "v %zu: %a %a %a\n", i / 3, g.xyz[i], g.xyz[i + 1], g.xyz[i + 2]);
    for (std::size_t i = 0; i + 2 < g.indices.size(); i += 3)
      std::fprintf(stderr, "triangle %zu: %u %u %u\n", i / 3, g.indices[i], g.indices[i + 1], g.indices[i + 2]);
    for (const auto& poly : g.polygons) {
      std::fprintf(stderr, "polygon:");
      for (float f : poly) std::fprintf(stderr, " %a", f);
      std::fprintf(stderr, "\n");
    }
  }
  if (current.rays && ray < current.rays->size()) {
    const volley_ray& r = (*current.rays)[ray];
    std::fprintf(stderr, "ray: org %a %a %a dir %a %a %a tmin %a tmax %a\n", r.org[0], r.org[1], r.org[2], r.dir[0],
                 r.dir[1], r.dir[2], r.tmin, r.tmax);
  }
}

}  // namespace

[[noreturn]] void finding(const char* what, std::size_t ray) {
  std::fprintf(stderr, "fuzz_capi: %s (ray %zu)\n", what, ray);
  print_case(ray);
  std::abort();
}

float coordinate(FuzzedDataProvider& in) {
  static const float kSpecial[] = {0.0f,    -0.0f,   1e-40f, -1e-40f, 1e-30f, 1e30f,
                                   -1e30f,  3e38f,   1e6f,   -1e6f,   0.1f,   std::numeric_limits<float>::infinity(),
                                   -std::numeric_limits<float>::infinity(), std::numeric_limits<float>::quiet_NaN()};
  const int kind = in.ConsumeIntegralInRange(0, 7);
  if (kind < 5) return 0.5f * static_cast<float>(in.ConsumeIntegralInRange(-8, 8));
  if (kind == 5) return kSpecial[in.ConsumeIntegralInRange<std::size_t>(0, std::size(kSpecial) - 1)];
  if (kind == 6) return static_cast<float>(in.ConsumeIntegralInRange(-256, 256)) / 16.0f;
  float f;
  const std::uint32_t bits = in.ConsumeIntegral<std::uint32_t>();
  std::memcpy(&f, &bits, 4);
  return f;
}

Geometry make_geometry(FuzzedDataProvider& in) {
  Geometry g;
  const std::size_t vertices = in.ConsumeIntegralInRange<std::size_t>(0, 48);
  for (std::size_t i = 0; i < 3 * vertices; ++i) g.xyz.push_back(coordinate(in));
  const std::size_t triangles = in.ConsumeIntegralInRange<std::size_t>(0, 64);
  for (std::size_t i = 0; i < 3 * triangles; ++i)
    // Now and then an index out of range (rejected as a whole).
    g.indices.push_back(in.ConsumeIntegralInRange<std::uint32_t>(0, static_cast<std::uint32_t>(vertices) + (i % 97 == 96)));
  const int polygons = in.ConsumeIntegralInRange(0, 2);
  for (int p = 0; p < polygons; ++p) {
    // Planar by construction most of the time: z = a x + b y + c on small values.
    const int n = in.ConsumeIntegralInRange(0, 7);
    const float a = coordinate(in), b = coordinate(in), c = coordinate(in);
    std::vector<float> poly;
    for (int k = 0; k < n; ++k) {
      const float x = coordinate(in), y = coordinate(in);
      poly.insert(poly.end(), {x, y, in.ConsumeBool() ? a * x + b * y + c : coordinate(in)});
    }
    g.polygons.push_back(poly);
  }
  return g;
}

volley_status add(volley_scene* scene, const Geometry& g, std::uint32_t* first_triangle) {
  volley_status first_error = VOLLEY_OK;
  const volley_status s = volley_scene_add_triangles(scene, g.xyz.data(), g.xyz.size() / 3, g.indices.data(),
                                                     g.indices.size() / 3, first_triangle);
  if (s != VOLLEY_OK) first_error = s;
  for (const auto& poly : g.polygons) {
    const volley_status p = volley_scene_add_polygon(scene, poly.data(), poly.size() / 3, nullptr);
    if (p != VOLLEY_OK && first_error == VOLLEY_OK) first_error = p;
  }
  return first_error;
}

volley_ray make_ray(FuzzedDataProvider& in, const Geometry& g) {
  volley_ray r;
  for (float& o : r.org) o = coordinate(in);
  const std::size_t vertices = g.xyz.size() / 3;
  if (vertices > 0 && in.ConsumeBool()) {
    // Aimed exactly at a vertex, or at the midpoint of two.
    const std::size_t a = in.ConsumeIntegralInRange<std::size_t>(0, vertices - 1);
    const std::size_t b = in.ConsumeBool() ? a : in.ConsumeIntegralInRange<std::size_t>(0, vertices - 1);
    for (int k = 0; k < 3; ++k) r.dir[k] = 0.5f * (g.xyz[3 * a + k] + g.xyz[3 * b + k]) - r.org[k];
  } else {
    for (float& d : r.dir) d = coordinate(in);
  }
  r.tmin = in.ConsumeBool() ? 0.0f : coordinate(in);
  r.tmax = in.ConsumeBool() ? std::numeric_limits<float>::infinity() : coordinate(in);
  return r;
}

}  // namespace fuzz_capi
