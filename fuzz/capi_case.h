// fuzz_capi's input: what the fuzzer's bytes build (geometry, rays) and how a finding is
// reported (the case printed, then abort, so that libFuzzer saves the input).
#pragma once
#include <fuzzer/FuzzedDataProvider.h>

#include <cstddef>
#include <cstdint>
#include <vector>

#include "volley/volley.h"

namespace fuzz_capi {

struct Geometry {
  std::vector<float> xyz;
  std::vector<std::uint32_t> indices;
  std::vector<std::vector<float>> polygons;
};

struct Case {
  const Geometry* geometry = nullptr;
  const std::vector<volley_ray>* rays = nullptr;
  int test = 0, isa = 0, robust = 0, reference_double = 0;
  std::uint32_t first_triangle = VOLLEY_INVALID_PRIM;  ///< the triangles' geometry id, if added
};
/// What the current input built, printed with a finding (the input itself is saved too).
extern Case current;

/// Prints `what`, the current case and ray `ray` of it, and aborts.
[[noreturn]] void finding(const char* what, std::size_t ray);

/// A coordinate: mostly small exact values (so that vertices coincide, edges are shared
/// and rays hit vertices exactly), sometimes an extreme or arbitrary float.
float coordinate(FuzzedDataProvider& in);
/// Vertices, triangles (now and then an index out of range) and up to two polygons.
Geometry make_geometry(FuzzedDataProvider& in);
/// Adds `g` to `scene`; returns the status of the first call that failed, else VOLLEY_OK.
/// The triangles' geometry id goes to *first_triangle when they were added.
volley_status add(volley_scene* scene, const Geometry& g, std::uint32_t* first_triangle = nullptr);
/// A ray: arbitrary, or aimed exactly at a vertex of `g` or the midpoint of two.
volley_ray make_ray(FuzzedDataProvider& in, const Geometry& g);

}  // namespace fuzz_capi
