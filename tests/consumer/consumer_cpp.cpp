// The C++ side of the consumer: builds tests/consumer/scene.h with volley::Accel for every
// test and every ISA this CPU has, and checks single rays, packets of 4, 8 and 16 (with
// partial packets), streams and occlusion against the exact answers; then the errors
// (volley::Error caught across the library boundary), names and info; then the C API from
// several threads (thread-local errors, concurrent queries).
#include <volley/accel.h>
#include <volley/options.h>
#include <volley/packet.h>
#include <volley/volley.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "scene.h"

namespace {

int failures = 0;

void check(bool ok, const std::string& what) {
  if (!ok) {
    ++failures;
    if (failures <= 20) std::printf("FAIL: %s\n", what.c_str());
  }
}

bool same(const volley::Hit& a, const volley::Hit& b) { return std::memcmp(&a, &b, sizeof a) == 0; }

std::vector<volley::Ray> grid_rays() {
  std::vector<volley::Ray> rays(SCENE_RAYS);
  for (int i = 0; i < SCENE_RAYS; ++i) {
    const volley_ray r = scene_ray(i);
    rays[i] = {{r.org[0], r.org[1], r.org[2]}, r.tmin, {r.dir[0], r.dir[1], r.dir[2]}, r.tmax};
  }
  return rays;
}

void add_scene(volley::Accel& accel) {
  const std::uint32_t floor = accel.add_triangles(kFloorXyz, 4, kFloorIndices, 2);
  const std::uint32_t table = accel.add_triangles(kTableXyz, 4, kTableIndices, 2);
  const std::uint32_t polygon = accel.add_polygon(kPolygonXyz, 6);
  check(floor == 0 && table == 1 && polygon == 2, "geometry ids 0, 1, 2");
}

/// The hit point from (u, v) is the ray's point at t (triangles only).
bool barycentrics_fit(const volley::Ray& r, const volley::Hit& h) {
  if (h.geom == 2) return h.u == 0.0f && h.v == 0.0f;
  const float* xyz = h.geom == 0 ? kFloorXyz : kTableXyz;
  const std::uint32_t* idx = (h.geom == 0 ? kFloorIndices : kTableIndices) + 3 * h.prim;
  for (int k = 0; k < 3; ++k) {
    const float p = (1 - h.u - h.v) * xyz[3 * idx[0] + k] + h.u * xyz[3 * idx[1] + k] + h.v * xyz[3 * idx[2] + k];
    if (std::fabs(p - (r.org[k] + h.t * r.dir[k])) > 1e-4f) return false;
  }
  return true;
}

template <int K>
void check_packets(const volley::Accel& accel, const std::vector<volley::Ray>& rays,
                   const std::vector<volley::Hit>& single, const std::string& label) {
  volley::RayPacket<K> packet;
  volley::HitPacket<K> hits;
  // Partial packets: runs of K - 1 lanes, so the last lanes are inert and inactive.
  for (int count : {K, K - 1}) {
    for (std::size_t i = 0; i < rays.size(); i += count) {
      const int n = int(std::min<std::size_t>(count, rays.size() - i));
      volley::load(packet, rays.data() + i, n);
      volley::reset(hits);
      accel.intersect(packet, hits);
      for (int l = 0; l < n; ++l)
        check(same(volley::hit_of(hits, l), single[i + l]), label + " packet" + std::to_string(K) + " ray " + std::to_string(i + l));
      for (int l = n; l < K; ++l) check(hits.prim[l] == volley::kInvalidPrim, label + " inactive lane written");
      const std::uint32_t blocked = accel.occluded(packet);
      for (int l = 0; l < K; ++l)
        check(((blocked >> l) & 1u) == (l < n && single[i + l].hit() ? 1u : 0u),
              label + " occluded packet" + std::to_string(K) + " ray " + std::to_string(i + l));
    }
  }
}

void check_accel(volley::TriangleTest test, volley::Isa isa) {
  const std::string label = std::string(volley::to_string(test)) + "/" + std::string(volley::to_string(isa));
  volley::Accel accel;
  add_scene(accel);
  try {
    accel.commit({test, isa});
  } catch (const volley::Error& e) {
    std::printf("skip %s: %s\n", label.c_str(), e.what());  // this CPU lacks the ISA
    return;
  }
  const volley::AccelInfo info = accel.info();
  check(info.triangles == 4 && info.polygons == 1 && info.test == test && info.isa == isa, label + " info");

  const std::vector<volley::Ray> rays = grid_rays();
  std::vector<volley::Hit> single(rays.size());
  int hits = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    single[i] = accel.intersect(rays[i]);
    float t;
    const volley_ray r = scene_ray(int(i));
    const std::uint32_t prim = scene_expected_prim(&r, &t);
    check(single[i].prim == scene_local(prim) && single[i].geom == scene_geometry(prim) && scene_t_close(single[i].t, t),
          label + " ray " + std::to_string(i) + ": geom " + std::to_string(single[i].geom) + " prim " +
              std::to_string(single[i].prim) + " t " + std::to_string(single[i].t) + ", expected scene primitive " +
              std::to_string(prim) + " t " + std::to_string(t));
    check(!single[i].hit() || barycentrics_fit(rays[i], single[i]), label + " barycentrics of ray " + std::to_string(i));
    check(accel.occluded(rays[i]) == single[i].hit(), label + " occluded ray " + std::to_string(i));
    // Occlusion is bounded by tmax: below the polygon only the polygon can block.
    volley::Ray shortened = rays[i];
    shortened.tmax = 3.5f;
    check(accel.occluded(shortened) == (prim == 4), label + " occluded with tmax 3.5, ray " + std::to_string(i));
    hits += single[i].hit();
  }
  check(hits > SCENE_RAYS / 2, label + " most rays hit");

  check_packets<4>(accel, rays, single, label);
  check_packets<8>(accel, rays, single, label);
  check_packets<16>(accel, rays, single, label);

  std::vector<volley::Hit> stream(rays.size());
  accel.intersect(rays.data(), rays.size(), stream.data());
  std::vector<std::uint8_t> blocked(rays.size());
  accel.occluded(rays.data(), rays.size(), blocked.data());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    check(same(stream[i], single[i]), label + " stream ray " + std::to_string(i));
    check(blocked[i] == (single[i].hit() ? 1 : 0), label + " occluded stream ray " + std::to_string(i));
  }

  // Saved and mapped back: the same answers, from a structure that was not built here.
  const std::string path = "consumer_cpp_scene.vacc";
  accel.save(path);
  const volley::Accel loaded = volley::Accel::load(path);
  check(loaded.info().loaded && loaded.info().isa == isa, label + " loaded info");
  for (std::size_t i = 0; i < rays.size(); ++i) check(same(loaded.intersect(rays[i]), single[i]), label + " loaded ray " + std::to_string(i));
  std::remove(path.c_str());
}

void check_errors() {
  const float nan_xyz[] = {0, 0, 0, 1, 0, 0, 0, std::nanf(""), 0};
  const std::uint32_t bad_indices[] = {0, 1, 3};
  const std::uint32_t indices[] = {0, 1, 2};
  volley::Accel accel;
  auto throws = [](auto&& f) {
    try {
      f();
    } catch (const volley::Error& e) {  // thrown in libvolley, caught here: typeinfo is shared
      return std::strlen(e.what()) > 0;
    }
    return false;
  };
  check(throws([&] { accel.add_triangles(nan_xyz, 3, indices, 1); }), "NaN vertex throws volley::Error");
  check(throws([&] { accel.add_triangles(kFloorXyz, 3, bad_indices, 1); }), "index out of range throws");
  const float skew[] = {0, 0, 0, 1, 0, 0, 1, 1, 0.5f, 0, 1, 0};
  check(throws([&] { accel.add_polygon(skew, 4); }), "non-planar polygon throws");
  volley::Accel fresh;
  fresh.add_triangles(kFloorXyz, 4, kFloorIndices, 2);
  check(throws([&] { fresh.intersect(volley::Ray{{0, 0, 1}, 0, {0, 0, -1}, 10}); }), "query before commit throws");
  check(throws([&] { fresh.save("consumer_cpp_uncommitted.vacc"); }), "save before commit throws");
  check(throws([&] { (void)volley::Accel::load("no_such_file.vacc"); }), "load of a missing file throws");

  check(volley::parse_isa("avx2") == volley::Isa::avx2 && !volley::parse_isa("mmx"), "parse_isa");
  check(volley::parse_triangle_test("moller") == volley::TriangleTest::moller, "parse_triangle_test");
  check(volley::to_string(volley::Isa::sse42) == "sse4.2", "to_string(Isa)");
}

/// The C API from several threads: each thread's last error is its own, and a committed
/// scene answers concurrent queries.
void check_c_api_threads() {
  volley_scene* scene = nullptr;
  check(volley_scene_create(&scene) == VOLLEY_OK, "C: create");
  volley_scene_add_triangles(scene, kFloorXyz, 4, kFloorIndices, 2, nullptr);
  volley_scene_add_triangles(scene, kTableXyz, 4, kTableIndices, 2, nullptr);
  volley_scene_add_polygon(scene, kPolygonXyz, 6, nullptr);
  check(volley_scene_commit(scene, VOLLEY_TEST_WATERTIGHT, VOLLEY_ISA_AUTO) == VOLLEY_OK, "C: commit");

  check(volley_intersect1(scene, nullptr, nullptr) == VOLLEY_ERROR_INVALID_ARGUMENT, "C: NULL ray");
  const std::string main_error = volley_last_error();
  std::vector<std::thread> threads;
  std::vector<int> wrong(4, 0);
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      if (std::strlen(volley_last_error()) != 0) ++wrong[t];  // a new thread starts with no error
      volley_scene* none = nullptr;
      if (volley_scene_commit(none, VOLLEY_TEST_WATERTIGHT, VOLLEY_ISA_AUTO) != VOLLEY_ERROR_INVALID_ARGUMENT ||
          std::strstr(volley_last_error(), "volley_scene_commit: scene is NULL") == nullptr)
        ++wrong[t];
      for (int i = t; i < SCENE_RAYS; i += 4) {
        const volley_ray r = scene_ray(i);
        volley_hit h;
        float expected_t;
        const uint32_t prim = scene_expected_prim(&r, &expected_t);
        if (volley_intersect1(scene, &r, &h) != VOLLEY_OK || h.prim != scene_local(prim) ||
            h.geom != scene_geometry(prim))
          ++wrong[t];
      }
    });
  }
  for (std::thread& th : threads) th.join();
  for (int t = 0; t < 4; ++t) check(wrong[t] == 0, "C: fresh error state and concurrent queries, thread " + std::to_string(t));
  check(main_error == volley_last_error(), "C: other threads' errors leave this thread's message alone");
  volley_scene_destroy(scene);
}

/// The queries beyond the first hit through the installed C++ headers: the scene's floor
/// and table seen straight down through their shared diagonals, and the floor's distance.
void check_queries() {
  volley::Accel accel;
  add_scene(accel);
  accel.commit();
  const volley::Ray down{{0.5f, 0.5f, 5.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, 100.0f};
  volley::Hit hits[4];
  check(accel.intersect_all(down, hits, 4) == 2, "intersect_all: one hit per surface through shared diagonals");
  check(hits[0].t == 4.0f && hits[1].t == 5.0f, "intersect_all: nearest first");
  check(accel.count_intersections(down) == 2, "count_intersections");
  const volley::HitLists lists = accel.intersect_all(&down, 1, 1);
  check(lists.offsets.size() == 2 && lists.offsets[1] == 2, "intersect_all batch offsets");
  const float above[3] = {-1.9f, 1.9f, 0.25f};
  const volley::ClosestPoint c = accel.closest_point(above);
  check(c.found() && c.geom == 0 && std::fabs(c.distance - 0.25f) < 1e-6f, "closest_point on the floor");
  check(!accel.contains(above), "contains: an open scene, above it");
}

}  // namespace

int main() {
  for (volley::TriangleTest test : {volley::TriangleTest::watertight, volley::TriangleTest::plane, volley::TriangleTest::moller})
    for (volley::Isa isa : {volley::Isa::scalar, volley::Isa::sse42, volley::Isa::avx2, volley::Isa::avx512})
      check_accel(test, isa);
  check_errors();
  check_c_api_threads();
  check_queries();
  if (failures) {
    std::printf("consumer_cpp: %d failures\n", failures);
    return 1;
  }
  std::printf("consumer_cpp: all checks passed (volley %s)\n", volley_version());
  return 0;
}
