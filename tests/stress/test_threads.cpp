// Threads: one committed scene queried by 8 threads at once in every form, two renders of
// one scene at once, and the C API's per-thread last error. Run under ThreadSanitizer
// (make test-tsan) this is the data-race check; in every build it checks that concurrent
// answers equal the single-threaded ones.
#include <doctest/doctest.h>

#include <atomic>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "../accel/accel_test_util.h"
#include "io/scene_loader.h"
#include "render/renderer.h"
#include "render/scene.h"
#include "volley/volley.h"

using namespace accel_test;

namespace {

constexpr int kThreads = 8;

/// Every form's answers for `rays`, as one vector of hits per form (occlusion as t = 0 /
/// miss). Packets use masks that vary with `salt`, so threads exercise partial packets.
std::vector<std::vector<Hit>> all_forms(const Accel& accel, const std::vector<Ray>& rays, std::uint32_t salt) {
  std::vector<std::vector<Hit>> out(6, std::vector<Hit>(rays.size()));
  for (std::size_t i = 0; i < rays.size(); ++i) {
    out[0][i] = accel.intersect(rays[i]);
    out[1][i] = accel.occluded(rays[i]) ? Hit{0.0f, 0.0f, 0.0f, 0} : Hit{};
  }
  auto packets = [&]<int K>(std::vector<Hit>& answers) {
    for (std::size_t first = 0; first < rays.size(); first += K) {
      volley::RayPacket<K> p;
      volley::HitPacket<K> h;
      const int count = static_cast<int>(std::min<std::size_t>(K, rays.size() - first));
      volley::load(p, rays.data() + first, count);
      volley::reset(h);
      // Every lane is traced in one of two passes: first the lanes of a salted mask, then
      // the rest (partial packets both times).
      const std::uint32_t mask = (0x9e3779b9u * (salt + static_cast<std::uint32_t>(first))) >> 7;
      const std::uint32_t all = p.active;
      for (const std::uint32_t pass : {all & mask, all & ~mask}) {
        p.active = pass;
        accel.intersect(p, h);
      }
      p.active = all;
      const std::uint32_t blocked = accel.occluded(p);
      for (int i = 0; i < count; ++i) {
        answers[first + static_cast<std::size_t>(i)] = volley::hit_of(h, i);
        if (K == 16) out[5][first + static_cast<std::size_t>(i)] = (blocked >> i) & 1u ? Hit{0.0f, 0.0f, 0.0f, 0} : Hit{};
      }
    }
  };
  packets.operator()<4>(out[2]);
  packets.operator()<8>(out[3]);
  packets.operator()<16>(out[4]);
  return out;
}

bool same(const std::vector<std::vector<Hit>>& a, const std::vector<std::vector<Hit>>& b) {
  for (std::size_t f = 0; f < a.size(); ++f)
    if (std::memcmp(a[f].data(), b[f].data(), a[f].size() * sizeof(Hit)) != 0) return false;
  return true;
}

}  // namespace

TEST_CASE("threads: 8 threads query one scene in every form and get the single-threaded answers") {
  const Soup soup = random_soup(3000, 71);
  const std::vector<Ray> rays = mixed_rays(40, 10.0f, 73);
  for (Isa isa : all_isas()) {
    CAPTURE(std::string(volley::to_string(isa)));
    const Accel accel = soup.accel(TriangleTest::watertight, isa);
    const auto want = all_forms(accel, rays, 0);
    std::vector<Hit> want_stream(rays.size());
    accel.intersect(rays.data(), rays.size(), want_stream.data());
    std::atomic<int> wrong{0};
    std::vector<std::thread> threads;
    for (int t = 0; t < kThreads; ++t)
      threads.emplace_back([&, t] {
        for (int rep = 0; rep < 2; ++rep) {
          // Same salt as the reference: the same lane splits, the same answers bit for bit.
          if (!same(all_forms(accel, rays, 0), want)) ++wrong;
          if (!same(all_forms(accel, rays, static_cast<std::uint32_t>(t + 1)), want)) {
            // Other lane splits may pick the other of two tied triangles; compare by agree().
            const auto got = all_forms(accel, rays, static_cast<std::uint32_t>(t + 1));
            for (std::size_t f = 0; f < got.size(); ++f)
              for (std::size_t i = 0; i < rays.size(); ++i) wrong += !agree(got[f][i], want[f][i]);
          }
          std::vector<Hit> stream(rays.size());
          accel.intersect(rays.data(), rays.size(), stream.data());
          if (std::memcmp(stream.data(), want_stream.data(), stream.size() * sizeof(Hit)) != 0) ++wrong;
        }
      });
    for (auto& th : threads) th.join();
    CHECK(wrong.load() == 0);
  }
}

TEST_CASE("threads: two threads own the two halves of one hit packet") {
  // A caller may split one packet's lanes between threads; each half is its own. Under
  // TSan any write of the other half's lanes (a whole-chunk store) is a reported race.
  const Soup soup = random_soup(2000, 79);
  const std::vector<Ray> rays = mixed_rays(30, 10.0f, 83);
  for (Isa isa : simd_isas()) {
    CAPTURE(std::string(volley::to_string(isa)));
    const Accel accel = soup.accel(TriangleTest::watertight, isa);
    for (std::size_t first = 0; first + 16 <= rays.size(); first += 16) {
      volley::RayPacket<16> low, high;
      volley::load(low, rays.data() + first, 16);
      high = low;
      low.active = 0x00ffu;
      high.active = 0xff00u;
      volley::HitPacket<16> shared;
      volley::reset(shared);
      std::thread a([&] { accel.intersect(low, shared); });
      std::thread b([&] { accel.intersect(high, shared); });
      a.join();
      b.join();
      for (int i = 0; i < 16; ++i) CHECK(agree(volley::hit_of(shared, i), accel.intersect(rays[first + i])));
    }
  }
}

TEST_CASE("threads: two renders of one scene at once give the single render's image") {
  const volley::io::SceneDesc desc =
      volley::io::load_scene(std::filesystem::path(VOLLEY_SOURCE_DIR) / "scenes" / "cornell.json", VOLLEY_SHARED_SCENES);
  const volley::render::Scene scene(desc, 24, 24, volley::Options{});
  volley::render::RenderOptions options;
  options.spp = 2;
  options.threads = 2;
  options.integrator = volley::render::IntegratorKind::path;
  const auto want = volley::render::render(scene, options);
  volley::render::RenderResult got[2];
  std::thread a([&] { got[0] = volley::render::render(scene, options); });
  std::thread b([&] { got[1] = volley::render::render(scene, options); });
  a.join();
  b.join();
  CHECK(got[0].image.pixels == want.image.pixels);
  CHECK(got[1].image.pixels == want.image.pixels);
}

TEST_CASE("threads: the C API's last error belongs to the thread that failed") {
  std::atomic<int> wrong{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t)
    threads.emplace_back([&, t] {
      volley_scene* scene = nullptr;  // one per thread: adding is single-threaded
      if (volley_scene_create(&scene) != VOLLEY_OK) ++wrong;
      for (int rep = 0; rep < 200; ++rep) {
        // Each thread fails in its own way and must read back its own message.
        const std::uint32_t bad_index = 1000u + static_cast<std::uint32_t>(t);
        const float xyz[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
        const std::uint32_t idx[3] = {0, 1, bad_index};
        volley_scene* none = nullptr;
        const volley_status s = t % 2 ? volley_scene_add_triangles(none, xyz, 3, idx, 1, nullptr)
                                      : volley_scene_add_triangles(scene, xyz, 3, idx, 1, nullptr);
        const std::string message = volley_last_error();
        const bool ok = t % 2 ? s == VOLLEY_ERROR_INVALID_ARGUMENT && message.find("scene") != std::string::npos
                              : s == VOLLEY_ERROR_INVALID_GEOMETRY &&
                                    message.find(std::to_string(bad_index)) != std::string::npos;
        wrong += !ok;
      }
      volley_scene_destroy(scene);
    });
  for (auto& th : threads) th.join();
  CHECK(wrong.load() == 0);
}

TEST_CASE("threads: the stream forms on 0, 2 and 3 threads give the one-thread answers bit for bit") {
  const Soup soup = random_soup(3000, 79);
  const std::vector<Ray> rays = mixed_rays(5000, 10.0f, 83);  // several pieces of 1024 and a partial run
  const std::vector<std::uint32_t> masks(rays.size(), volley::kMaskAll);
  for (Isa isa : simd_isas()) {
    CAPTURE(std::string(volley::to_string(isa)));
    const Accel accel = soup.accel(TriangleTest::watertight, isa);
    std::vector<Hit> want(rays.size());
    std::vector<std::uint8_t> want_blocked(rays.size());
    accel.intersect(rays.data(), rays.size(), want.data());
    accel.occluded(rays.data(), rays.size(), want_blocked.data());
    for (int threads : {0, 2, 3}) {
      CAPTURE(threads);
      std::vector<Hit> hits(rays.size());
      std::vector<std::uint8_t> blocked(rays.size(), 7);
      accel.intersect(rays.data(), rays.size(), hits.data(), threads);
      CHECK(std::memcmp(hits.data(), want.data(), hits.size() * sizeof(Hit)) == 0);
      accel.intersect(rays.data(), masks.data(), rays.size(), hits.data(), threads);
      CHECK(std::memcmp(hits.data(), want.data(), hits.size() * sizeof(Hit)) == 0);
      accel.occluded(rays.data(), rays.size(), blocked.data(), threads);
      CHECK(blocked == want_blocked);
      accel.occluded(rays.data(), masks.data(), rays.size(), blocked.data(), threads);
      CHECK(blocked == want_blocked);
    }
    std::vector<Hit> hits(rays.size());
    CHECK_THROWS_AS(accel.intersect(rays.data(), rays.size(), hits.data(), -1), volley::Error);
  }
}

TEST_CASE("threads: callers on four threads at once, each running 3-thread batches twice, get the one-thread answers") {
  // Each calling thread keeps an arena per thread count (accel::arena_of): the second call
  // reuses it, and callers do not share one.
  const Soup soup = random_soup(3000, 89);
  const std::vector<Ray> rays = mixed_rays(5000, 10.0f, 97);
  const std::vector<Isa> isas = simd_isas();
  const Accel accel = soup.accel(TriangleTest::watertight, isas.empty() ? Isa::scalar : isas.back());
  std::vector<Hit> want(rays.size());
  std::vector<std::uint8_t> want_blocked(rays.size());
  accel.intersect(rays.data(), rays.size(), want.data());
  accel.occluded(rays.data(), rays.size(), want_blocked.data());
  std::atomic<int> wrong{0};
  std::vector<std::thread> callers;
  for (int t = 0; t < 4; ++t)
    callers.emplace_back([&] {
      for (int rep = 0; rep < 2; ++rep) {
        std::vector<Hit> hits(rays.size());
        std::vector<std::uint8_t> blocked(rays.size(), 7);
        accel.intersect(rays.data(), rays.size(), hits.data(), 3);
        accel.occluded(rays.data(), rays.size(), blocked.data(), 3);
        wrong += std::memcmp(hits.data(), want.data(), hits.size() * sizeof(Hit)) != 0;
        wrong += blocked != want_blocked;
      }
    });
  for (auto& c : callers) c.join();
  CHECK(wrong.load() == 0);
}
