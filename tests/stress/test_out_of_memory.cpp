// Out of memory during commit: a clean error from both APIs, never a crash. The test runs
// itself again as a child process whose address space is capped (RLIMIT_AS), adds a mesh
// that fits, and commits a structure that does not. Not in the sanitizer builds: their
// runtimes end the process on a failed operator new instead of throwing std::bad_alloc
// (compiler-rt's OPERATOR_NEW_BODY), so there is nothing of volley's to check there.
#include <doctest/doctest.h>
#include <oneapi/tbb/global_control.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "volley/accel.h"
#include "volley/volley.h"

namespace {

constexpr const char* kChildVariable = "VOLLEY_TEST_OOM_CHILD";
constexpr const char* kTestName = "out of memory: commit fails cleanly in the C++ and C APIs";
constexpr std::size_t kTriangles = 1'000'000;  // 36 MB of vertices; the build needs far more

/// A soup of kTriangles small triangles along a line (a real build, nothing degenerate).
void soup(std::vector<float>& xyz, std::vector<std::uint32_t>& idx) {
  xyz.resize(9 * kTriangles);
  idx.resize(3 * kTriangles);
  for (std::size_t t = 0; t < kTriangles; ++t) {
    const float x = static_cast<float>(t) * 0.01f;
    const float v[9] = {x, 0, 0, x + 0.5f, 0, 0, x, 0.5f, static_cast<float>(t % 7)};
    std::memcpy(&xyz[9 * t], v, sizeof v);
    for (int k = 0; k < 3; ++k) idx[3 * t + k] = static_cast<std::uint32_t>(3 * t + k);
  }
}

/// Caps this process's address space at its current size plus `extra` bytes.
void cap_memory(std::size_t extra) {
  std::ifstream statm("/proc/self/statm");
  std::size_t pages = 0;
  statm >> pages;
  const rlim_t limit = pages * static_cast<std::size_t>(sysconf(_SC_PAGESIZE)) + extra;
  const rlimit r{limit, limit};
  setrlimit(RLIMIT_AS, &r);
}

/// The child: exit 0 when both APIs report running out of memory as documented.
[[noreturn]] void child() {
  // One thread: worker stacks would count against the cap, and are not what is tested.
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  std::vector<float> xyz;
  std::vector<std::uint32_t> idx;
  soup(xyz, idx);
  int failures = 0;

  volley::Accel accel;
  accel.add_triangles(xyz.data(), 3 * kTriangles, idx.data(), kTriangles);
  volley_scene* scene = nullptr;
  volley_scene_create(&scene);
  volley_scene_add_triangles(scene, xyz.data(), 3 * kTriangles, idx.data(), kTriangles, nullptr);
  cap_memory(40u << 20);

  try {
    accel.commit();
    std::fprintf(stderr, "C++: commit succeeded under the cap\n");
    ++failures;
  } catch (const volley::OutOfMemory& e) {
    std::fprintf(stderr, "C++: %s\n", e.what());
    failures += std::strstr(e.what(), "out of memory") == nullptr;
    try {
      (void)accel.intersect(volley::Ray{{0, 0, 1}, 0, {0, 0, -1}, 10});
      ++failures;  // an uncommitted Accel must refuse queries
    } catch (const volley::Error&) {
    }
  }
  const volley_status s = volley_scene_commit(scene, VOLLEY_TEST_WATERTIGHT, VOLLEY_ISA_AUTO);
  std::fprintf(stderr, "C: %s: %s\n", volley_status_string(s), volley_last_error());
  failures += s != VOLLEY_ERROR_OUT_OF_MEMORY;
  volley_hit hit;
  const volley_ray ray{{0, 0, 1}, 0, {0, 0, -1}, 10};
  failures += volley_intersect1(scene, &ray, &hit) != VOLLEY_ERROR_NOT_COMMITTED;
  volley_scene_destroy(scene);
  std::_Exit(failures == 0 ? 0 : 1);
}

}  // namespace

TEST_CASE("out of memory: commit fails cleanly in the C++ and C APIs") {
#if defined(VOLLEY_SANITIZED)
  MESSAGE("not checked in a sanitizer build (its operator new aborts instead of throwing); make test checks it");
  return;
#endif
  if (std::getenv(kChildVariable)) child();
  const pid_t pid = fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    setenv(kChildVariable, "1", 1);
    const std::string filter = std::string("--test-case=") + kTestName;
    execl("/proc/self/exe", "test_stress", filter.c_str(), static_cast<char*>(nullptr));
    std::_Exit(127);
  }
  int status = 0;
  REQUIRE(waitpid(pid, &status, 0) == pid);
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
}
