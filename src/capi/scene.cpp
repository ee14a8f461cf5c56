// C API: scene lifetime, geometry input, commit and info. Input is validated here, before
// volley::Accel sees it, so that a rejected call leaves the scene exactly as it was.
#include "capi/scene.h"

#include <cmath>
#include <cstring>
#include <memory>
#include <string>

#include "capi/guard.h"
#include "simd/isa/dispatch.h"
#include "volley/volley.h"

namespace volley::capi {
namespace {

/// Prim ids available: kInvalidPrim itself is the miss marker.
constexpr std::uint64_t kMaxPrims = kInvalidPrim;

/// The integer a C caller passed as an enum. C allows any int there, C++ only the values
/// of the enum's range, so it is read as bytes: loading an out-of-range value as the enum
/// would itself be undefined (UBSan's enum check caught the package test's bad values).
template <class Enum>
int raw_value(const Enum& e) {
  static_assert(sizeof(Enum) == sizeof(int), "C enums are ints");
  int v;
  std::memcpy(&v, &e, sizeof v);
  return v;
}

/// The C++ test for a C enum value (as raw_value); fails for one outside the enum.
TriangleTest to_test(int test) {
  switch (test) {
    case VOLLEY_TEST_WATERTIGHT: return TriangleTest::watertight;
    case VOLLEY_TEST_PLANE: return TriangleTest::plane;
    case VOLLEY_TEST_MOLLER: return TriangleTest::moller;
  }
  fail(VOLLEY_ERROR_INVALID_ARGUMENT, "unknown triangle test " + std::to_string(test) +
                                          " (expected VOLLEY_TEST_WATERTIGHT, VOLLEY_TEST_PLANE or VOLLEY_TEST_MOLLER)");
}

/// The C++ ISA for a C enum value (as raw_value); fails for one outside the enum.
Isa to_isa(int isa) {
  switch (isa) {
    case VOLLEY_ISA_AUTO: return Isa::automatic;
    case VOLLEY_ISA_SCALAR: return Isa::scalar;
    case VOLLEY_ISA_SSE42: return Isa::sse42;
    case VOLLEY_ISA_AVX2: return Isa::avx2;
    case VOLLEY_ISA_AVX512: return Isa::avx512;
  }
  fail(VOLLEY_ERROR_INVALID_ARGUMENT, "unknown ISA " + std::to_string(isa) + " (expected a VOLLEY_ISA_* value)");
}

/// The C++ build quality for a C enum value (as raw_value); fails for one outside the enum.
volley::BuildQuality to_quality(int quality) {
  switch (quality) {
    case VOLLEY_BUILD_QUALITY_MEDIUM: return volley::BuildQuality::medium;
    case VOLLEY_BUILD_QUALITY_HIGH: return volley::BuildQuality::high;
  }
  fail(VOLLEY_ERROR_INVALID_ARGUMENT, "unknown build quality " + std::to_string(quality) +
                                          " (expected VOLLEY_BUILD_QUALITY_MEDIUM or VOLLEY_BUILD_QUALITY_HIGH)");
}

volley_triangle_test from_test(TriangleTest test) {
  switch (test) {
    case TriangleTest::plane: return VOLLEY_TEST_PLANE;
    case TriangleTest::moller: return VOLLEY_TEST_MOLLER;
    case TriangleTest::watertight: break;
  }
  return VOLLEY_TEST_WATERTIGHT;
}

volley_isa from_isa(Isa isa) {
  switch (isa) {
    case Isa::automatic: return VOLLEY_ISA_AUTO;
    case Isa::scalar: return VOLLEY_ISA_SCALAR;
    case Isa::sse42: return VOLLEY_ISA_SSE42;
    case Isa::avx2: return VOLLEY_ISA_AVX2;
    case Isa::avx512: return VOLLEY_ISA_AVX512;
  }
  return VOLLEY_ISA_AUTO;
}

/// Fails when `count` more primitives would run out of prim ids.
void require_prim_ids(const volley_scene& scene, std::uint64_t count) {
  if (count > kMaxPrims - scene.prims)
    fail(VOLLEY_ERROR_INVALID_ARGUMENT, "too many primitives: the scene has " + std::to_string(scene.prims) +
                                            ", adding " + std::to_string(count) + " would pass the limit of " +
                                            std::to_string(kMaxPrims) + " prim ids");
}

/// Fails with VOLLEY_ERROR_INVALID_GEOMETRY at the first non-finite coordinate.
void require_finite(const float* xyz, std::size_t vertex_count) {
  for (std::size_t i = 0; i < 3 * vertex_count; ++i)
    if (!std::isfinite(xyz[i]))
      fail(VOLLEY_ERROR_INVALID_GEOMETRY, "vertex " + std::to_string(i / 3) + " has a non-finite coordinate (" +
                                              "xyz[" + std::to_string(i) + "] = " + std::to_string(xyz[i]) + ")");
}

/// Fails when 3 * count does not fit in size_t (so no array of that size can exist).
void require_triple_fits(std::size_t count, const char* what) {
  if (count > SIZE_MAX / 3) fail(VOLLEY_ERROR_INVALID_ARGUMENT, std::string(what) + " is absurdly large");
}

}  // namespace

void fail_not_committed(const volley_scene* scene) {
  require_pointer(scene, "scene");
  fail(VOLLEY_ERROR_NOT_COMMITTED, "the scene changed (or was never committed): call volley_scene_commit first");
}

namespace {

// Both commit functions: the options checked and applied, errors named after `function`.
volley_status commit(volley_scene* scene, const volley_commit_options* in, const char* function) {
  return guarded(function, VOLLEY_ERROR_INTERNAL, [&] {
    require_pointer(scene, "scene");
    require_pointer(in, "options");
    volley::Options options;
    options.test = to_test(raw_value(in->test));
    options.isa = to_isa(raw_value(in->isa));
    options.robust = in->robust != 0;
    options.reference_double = in->reference_double != 0;
    options.refit = in->refit != 0;
    options.quality = to_quality(raw_value(in->quality));
    if (options.reference_double && (options.isa != volley::Isa::scalar || !options.robust))
      fail(VOLLEY_ERROR_INVALID_ARGUMENT, "reference_double needs VOLLEY_ISA_SCALAR and robust box tests");
    try {
      // The ISA commit would run (VOLLEY_ISA applied for auto), resolved here so that an
      // unsupported one gets its own status.
      options.isa = volley::simd::resolve_isa(options.isa);
    } catch (const std::invalid_argument& e) {
      fail(VOLLEY_ERROR_UNSUPPORTED_ISA, e.what());
    }
    scene->committed = false;
    scene->accel.commit(options);
    scene->committed = true;
  });
}

}  // namespace

}  // namespace volley::capi

using namespace volley::capi;

extern "C" {

int volley_isa_supported(volley_isa isa) {
  switch (raw_value(isa)) {
    case VOLLEY_ISA_AUTO:
    case VOLLEY_ISA_SCALAR: return 1;
    case VOLLEY_ISA_SSE42: return volley::simd::cpu_has(volley::Isa::sse42) ? 1 : 0;
    case VOLLEY_ISA_AVX2: return volley::simd::cpu_has(volley::Isa::avx2) ? 1 : 0;
    case VOLLEY_ISA_AVX512: return volley::simd::cpu_has(volley::Isa::avx512) ? 1 : 0;
  }
  return 0;
}

volley_status volley_scene_create(volley_scene** out) {
  return guarded("volley_scene_create", VOLLEY_ERROR_INTERNAL, [&] {
    require_pointer(out, "out");
    *out = new volley_scene;
  });
}

void volley_scene_destroy(volley_scene* scene) { delete scene; }

volley_status volley_scene_add_triangles(volley_scene* scene, const float* xyz, size_t vertex_count,
                                         const uint32_t* indices, size_t triangle_count, uint32_t* geometry) {
  return guarded("volley_scene_add_triangles", VOLLEY_ERROR_INVALID_GEOMETRY, [&] {
    require_pointer(scene, "scene");
    require_triple_fits(vertex_count, "vertex_count");
    require_triple_fits(triangle_count, "triangle_count");
    if (vertex_count > 0) require_pointer(xyz, "xyz");
    if (triangle_count > 0) require_pointer(indices, "indices");
    require_prim_ids(*scene, triangle_count);
    require_finite(xyz, vertex_count);
    for (std::size_t i = 0; i < 3 * triangle_count; ++i)
      if (indices[i] >= vertex_count)
        fail(VOLLEY_ERROR_INVALID_GEOMETRY, "triangle " + std::to_string(i / 3) + " uses vertex index " +
                                                std::to_string(indices[i]) + ", but there are only " +
                                                std::to_string(vertex_count) + " vertices");
    // Accel checks the same again; it never throws here, so a failure above leaves the
    // scene untouched (Accel::add_triangles itself may stop half-way through a mesh).
    const std::uint32_t id = scene->accel.add_triangles(xyz, vertex_count, indices, triangle_count);
    scene->prims += triangle_count;
    scene->committed = false;
    if (geometry) *geometry = id;
  });
}

volley_status volley_scene_add_polygon(volley_scene* scene, const float* xyz, size_t vertex_count,
                                       uint32_t* geometry) {
  return guarded("volley_scene_add_polygon", VOLLEY_ERROR_INVALID_GEOMETRY, [&] {
    require_pointer(scene, "scene");
    require_pointer(xyz, "xyz");
    require_triple_fits(vertex_count, "vertex_count");
    if (vertex_count < 3)
      fail(VOLLEY_ERROR_INVALID_GEOMETRY, "a polygon needs at least 3 vertices, got " + std::to_string(vertex_count));
    require_prim_ids(*scene, 1);
    require_finite(xyz, vertex_count);
    // Planarity and area: Accel's check (volley::Error -> VOLLEY_ERROR_INVALID_GEOMETRY);
    // it throws before it adds anything.
    const std::uint32_t id = scene->accel.add_polygon(xyz, vertex_count);
    scene->prims += 1;
    scene->committed = false;
    if (geometry) *geometry = id;
  });
}

volley_status volley_scene_add_instance(volley_scene* scene, const volley_scene* prototype, const float* transform,
                                        uint32_t* geometry) {
  return guarded("volley_scene_add_instance", VOLLEY_ERROR_INVALID_ARGUMENT, [&] {
    require_pointer(scene, "scene");
    require_pointer(prototype, "prototype");
    require_pointer(transform, "transform");
    if (prototype == scene) fail(VOLLEY_ERROR_INVALID_ARGUMENT, "a scene cannot instance itself");
    if (!prototype->committed) fail(VOLLEY_ERROR_NOT_COMMITTED, "commit the prototype first");
    // Accel checks the rest (itself, nested, non-finite or singular: volley::Error) before it adds anything.
    const std::uint32_t id = scene->accel.add_instance(prototype->accel, transform);
    scene->committed = false;
    if (geometry) *geometry = id;
  });
}

volley_status volley_scene_disable_geometry(volley_scene* scene, uint32_t geometry) {
  // (Accel's Error for an unknown id is an argument error here.)
  return guarded("volley_scene_disable_geometry", VOLLEY_ERROR_INVALID_ARGUMENT, [&] {
    require_pointer(scene, "scene");
    scene->accel.disable_geometry(geometry);
    scene->committed = false;
  });
}

volley_status volley_scene_update_vertices(volley_scene* scene, uint32_t geometry, const float* xyz,
                                          size_t vertex_count) {
  // (Accel's Error: an unknown id or another vertex count is an argument error; the
  // coordinates are checked here first.)
  return guarded("volley_scene_update_vertices", VOLLEY_ERROR_INVALID_ARGUMENT, [&] {
    require_pointer(scene, "scene");
    require_pointer(xyz, "xyz");
    require_triple_fits(vertex_count, "vertex_count");
    require_finite(xyz, vertex_count);
    scene->accel.update_vertices(geometry, xyz, vertex_count);
    scene->committed = false;
  });
}

volley_status volley_scene_enable_geometry(volley_scene* scene, uint32_t geometry) {
  return guarded("volley_scene_enable_geometry", VOLLEY_ERROR_INVALID_ARGUMENT, [&] {
    require_pointer(scene, "scene");
    scene->accel.enable_geometry(geometry);
    scene->committed = false;
  });
}

volley_status volley_scene_set_geometry_mask(volley_scene* scene, uint32_t geometry, uint32_t mask) {
  return guarded("volley_scene_set_geometry_mask", VOLLEY_ERROR_INVALID_ARGUMENT, [&] {
    require_pointer(scene, "scene");
    scene->accel.set_geometry_mask(geometry, mask);
    scene->committed = false;
  });
}

void volley_commit_options_default(volley_commit_options* options) {
  if (options == nullptr) return;
  options->test = VOLLEY_TEST_WATERTIGHT;
  options->isa = VOLLEY_ISA_AUTO;
  options->robust = 1;
  options->reference_double = 0;
  options->refit = 1;
  options->quality = VOLLEY_BUILD_QUALITY_MEDIUM;
}

volley_status volley_scene_commit(volley_scene* scene, volley_triangle_test test, volley_isa isa) {
  volley_commit_options options;
  volley_commit_options_default(&options);
  std::memcpy(&options.test, &test, sizeof test);  // bytes, not enum loads (raw_value)
  std::memcpy(&options.isa, &isa, sizeof isa);
  return commit(scene, &options, "volley_scene_commit");
}

volley_status volley_scene_commit_ex(volley_scene* scene, const volley_commit_options* options) {
  return commit(scene, options, "volley_scene_commit_ex");
}

volley_status volley_scene_get_info(const volley_scene* scene, volley_scene_info* info) {
  return guarded("volley_scene_get_info", VOLLEY_ERROR_INTERNAL, [&] {
    require_committed(scene);
    require_pointer(info, "info");
    const volley::AccelInfo a = scene->accel.info();
    volley_scene_info out{};
    out.triangles = a.triangles;
    out.degenerate = a.degenerate;
    out.polygons = a.polygons;
    out.nodes = a.nodes;
    out.leaves = a.leaves;
    out.depth = a.depth;
    out.bytes = a.bytes;
    out.build_seconds = a.build_seconds;
    out.width = a.width;
    out.block_width = a.block_width;
    out.test = from_test(a.test);
    out.isa = from_isa(a.isa);
    out.geometries = a.geometries;
    out.disabled = a.disabled;
    out.refitted = a.refitted ? 1 : 0;
    out.sah_growth = a.sah_growth;
    out.loaded = a.loaded ? 1 : 0;
    out.layers = a.layers;
    out.instances = a.instances;
    out.instanced_triangles = a.instanced_triangles;
    out.load_seconds = a.load_seconds;
    out.quality = a.quality == volley::BuildQuality::high ? VOLLEY_BUILD_QUALITY_HIGH : VOLLEY_BUILD_QUALITY_MEDIUM;
    out.references = a.references;
    *info = out;
  });
}

volley_status volley_scene_save(const volley_scene* scene, const char* path) {
  return guarded("volley_scene_save", VOLLEY_ERROR_FILE, [&] {
    require_pointer(path, "path");
    require_committed(scene);
    scene->accel.save(path);
  });
}

volley_status volley_scene_load(const char* path, volley_scene** out) {
  return guarded("volley_scene_load", VOLLEY_ERROR_FILE, [&] {
    require_pointer(path, "path");
    require_pointer(out, "out");
    auto scene = std::make_unique<volley_scene>();
    scene->accel = volley::Accel::load(path);
    const volley::AccelInfo info = scene->accel.info();
    scene->prims = info.triangles + info.polygons;
    scene->committed = true;
    *out = scene.release();
  });
}

}  // extern "C"
