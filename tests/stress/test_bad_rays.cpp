// Numerical stress suite (docs/accuracy.md, stress catalogue) — bad rays and the tmin = 0 edge:
//   11 NaN / Inf origins or directions, zero directions, tmin > tmax, tmin == tmax, NaN tmin
//      or tmax miss; tmax = +inf is an ordinary ray; in packets and streams the good lanes
//      give exactly their single-ray answers (no crash, no endless traversal)
//   12 origin exactly on a triangle with tmin = 0: the behaviour is pinned below and is the
//      same for every ISA and mode
//   13 all of it for the scalar oracle and every ISA this CPU has
// VOLLEY_STRESS_LONG=1 runs many more rays per case (see stress_util.h).
#include <doctest/doctest.h>

#include <random>
#include <sstream>

#include "closed_meshes.h"
#include "stress_util.h"

using namespace stress;

namespace {

/// Same closest-hit answer: both miss, or both hit the same prim at the same t, u, v, or
/// (with `ulp_ties`) two different prims within 2 ulps of t: the rays aim at shared vertices
/// and edges, where the triangles meeting there give t values 1-2 ulps apart and packets and
/// streams sometimes report the farther one (see the skipped case below).
bool same(const Hit& a, const Hit& b, bool ulp_ties = true) {
  if (a.hit() != b.hit()) return false;
  if (!a.hit()) return true;
  if (a.prim == b.prim) return a.t == b.t && a.u == b.u && a.v == b.v;
  return ulp_ties ? std::fabs(a.t - b.t) <= 2.5e-7f * std::fabs(b.t) : a.t == b.t;
}

/// The bad-ray variants of `r`, each of which must miss.
std::vector<Ray> poison(const Ray& r) {
  std::vector<Ray> out;
  for (int c = 0; c < 3; ++c)
    for (float bad : {kNaN, kInf, -kInf}) {
      Ray o = r;
      o.org[c] = bad;
      out.push_back(o);
      Ray d = r;
      d.dir[c] = bad;
      out.push_back(d);
    }
  for (float z : {0.0f, -0.0f}) {
    Ray zero = r;
    zero.dir[0] = zero.dir[1] = zero.dir[2] = z;
    out.push_back(zero);
  }
  Ray reversed = r;  // tmin > tmax
  reversed.tmin = 5.0f, reversed.tmax = 1.0f;
  out.push_back(reversed);
  Ray empty = r;  // tmin == tmax: the half-open range [t, t) is empty
  empty.tmin = empty.tmax = 1.0f;
  out.push_back(empty);
  Ray nan_min = r, nan_max = r, inf_min = r;
  nan_min.tmin = kNaN, nan_max.tmax = kNaN, inf_min.tmin = kInf;
  out.push_back(nan_min), out.push_back(nan_max), out.push_back(inf_min);
  return out;
}

}  // namespace

TEST_CASE("stress 11/13/14: bad rays miss and leave the good lanes of their packet or stream undisturbed") {
  const ClosedMesh cube = grid_cube(8);
  std::size_t exact = 0, origins = 0;
  std::vector<Ray> good = closed_mesh_rays(cube, 0.0f, exact, origins);
  // tmax = +inf is already the norm; bound half of them so that tmax is exercised too.
  for (std::size_t i = 0; i < good.size(); i += 2) good[i].tmax = 1.5f;
  if (!long_mode()) good.resize(std::min<std::size_t>(good.size(), 2000));
  const std::size_t variants = poison(good[0]).size();
  // Coverage of the generator: every kind of bad value in origin and direction.
  {
    std::size_t nan_o = 0, inf_o = 0, nan_d = 0, inf_d = 0, zero_d = 0, reversed = 0;
    for (const Ray& b : poison(good[0])) {
      for (int c = 0; c < 3; ++c) {
        nan_o += std::isnan(b.org[c]), inf_o += std::isinf(b.org[c]);
        nan_d += std::isnan(b.dir[c]), inf_d += std::isinf(b.dir[c]);
      }
      zero_d += b.dir[0] == 0 && b.dir[1] == 0 && b.dir[2] == 0;
      reversed += b.tmin > b.tmax;
    }
    CHECK(nan_o == 3);
    CHECK(inf_o == 6);
    CHECK(nan_d == 3);
    CHECK(inf_d == 6);
    CHECK(zero_d == 2);
    CHECK(reversed >= 1);
  }
  // Mixed: every third ray replaced by a bad variant (cycling through them).
  std::vector<Ray> mixed;
  std::vector<std::uint8_t> is_bad;
  std::vector<std::size_t> source;
  for (std::size_t i = 0; i < good.size(); ++i) {
    if (i % 3 == 1) {
      mixed.push_back(poison(good[i])[(i / 3) % variants]);
      is_bad.push_back(1);
    } else {
      mixed.push_back(good[i]);
      is_bad.push_back(0);
    }
    source.push_back(i);
  }
  for (TriangleTest test : kTests)
    for (Isa isa : isas()) {
      const Accel accel = cube.mesh.accel(test, isa);
      // Single-ray answers of the good rays, and every bad variant alone.
      std::vector<Hit> want(good.size());
      std::vector<std::uint8_t> want_occ(good.size());
      for (std::size_t i = 0; i < good.size(); ++i) want[i] = accel.intersect(good[i]), want_occ[i] = accel.occluded(good[i]);
      std::size_t bad_hits = 0;
      for (std::size_t i = 0; i < good.size(); i += 97)
        for (const Ray& b : poison(good[i])) bad_hits += accel.intersect(b).hit() || accel.occluded(b);
      INFO(name(test), " ", name(isa));
      CHECK(bad_hits == 0);
      for (Mode mode : kModes) {
        const Answers a = trace(accel, mixed, mode);
        std::size_t bad_hit = 0, good_changed = 0, nan = 0;
        for (std::size_t i = 0; i < mixed.size(); ++i) {
          nan += std::isnan(a.hits[i].t);
          if (is_bad[i])
            bad_hit += a.hits[i].hit() || a.occluded[i];
          else
            good_changed += !same(a.hits[i], want[i]) || a.occluded[i] != want_occ[i];
        }
        // The same good rays without bad neighbours, to tell poisoning from a plain
        // packet/stream-versus-single difference.
        const Answers clean = trace(accel, good, mode);
        std::size_t clean_changed = 0;
        for (std::size_t i = 0; i < good.size(); ++i) {
          clean_changed += !same(clean.hits[i], want[i]) || clean.occluded[i] != want_occ[i];
        }
        INFO(name(mode));
        CHECK(clean_changed == 0);
        CHECK(bad_hit == 0);
        CHECK(good_changed == 0);
        CHECK(nan == 0);
      }
      // Inactive lanes holding garbage are ignored, and the hits they map to are not written.
      volley::RayPacket<16> p;
      volley::HitPacket<16> h;
      volley::load(p, good.data(), 16);
      for (int i = 1; i < 16; i += 2) {
        p.ox[i] = kNaN, p.dy[i] = kInf, p.tmin[i] = 3, p.tmax[i] = -1;
        p.active &= ~(1u << i);
      }
      volley::reset(h);
      for (int i = 1; i < 16; i += 2) h.t[i] = -7.0f, h.prim[i] = 12345u;
      accel.intersect(p, h);
      const std::uint32_t occ = accel.occluded(p);
      for (int i = 0; i < 16; ++i) {
        if (i % 2) {
          CHECK(h.t[i] == -7.0f);
          CHECK(h.prim[i] == 12345u);
          CHECK(((occ >> i) & 1u) == 0u);
        } else {
          CHECK(same(volley::hit_of(h, i), want[i]));
        }
      }
    }
}

TEST_CASE("stress 12/13: origin exactly on a triangle with tmin = 0 (pinned behaviour)") {
  // One big triangle in z = 0 (float-exact), origins exactly on it (z = 0, x and y inside),
  // directions leaving it (dz > 0), entering it (dz < 0, i.e. crossing the plane at t = 0)
  // and in its plane (dz = ±0). A second triangle at z = 1 and at z = -1 to be hit otherwise.
  Mesh mesh;
  mesh.triangle(mesh.vertex(-4, -4, 0), mesh.vertex(4, -4, 0), mesh.vertex(0, 4, 0));
  mesh.triangle(mesh.vertex(-40, -40, 1), mesh.vertex(40, -40, 1), mesh.vertex(0, 40, 1));
  mesh.triangle(mesh.vertex(-40, -40, -1), mesh.vertex(40, -40, -1), mesh.vertex(0, 40, -1));
  std::mt19937 rng(12);
  std::uniform_real_distribution<float> u(-1, 1);
  std::vector<Ray> rays;
  enum Kind { leaving, entering, in_plane };
  std::vector<Kind> kind;
  const int per = long_mode() ? 100000 : 200;
  for (int k = 0; k < per; ++k) {
    const float o[3] = {u(rng), u(rng) - 1.0f, 0.0f};
    const float up[3] = {u(rng), u(rng), 0.1f + std::fabs(u(rng))};
    const float down[3] = {up[0], up[1], -up[2]};
    const float flat[3] = {up[0], up[1], (k % 2) ? 0.0f : -0.0f};
    rays.push_back(make_ray(o, up)), kind.push_back(leaving);
    rays.push_back(make_ray(o, down)), kind.push_back(entering);
    rays.push_back(make_ray(o, flat)), kind.push_back(in_plane);
  }
  for (TriangleTest test : kTests) {
    // Single rays of the first ISA of each agreement group (the scalar oracle, or for fused
    // moller and watertight the first of AVX2, AVX-512): fused t may differ from unfused t
    // in the last bits.
    std::vector<Hit> oracle[kAgreementGroups];
    std::size_t self[3] = {0, 0, 0}, other[3] = {0, 0, 0}, none[3] = {0, 0, 0};
    for (Isa isa : isas())
      for (Mode mode : kModes) {
        const Accel accel = mesh.accel(test, isa);
        const Answers a = trace(accel, rays, mode);
        const int group = agreement_group(test, isa);
        if (oracle[group].empty()) {
          oracle[group] = a.hits;
          for (std::size_t i = 0; i < rays.size(); ++i) {
            const Hit& h = a.hits[i];
            if (group == 0) (h.prim == 0 ? self : h.hit() ? other : none)[kind[i]]++;
            // Moller's groups may differ in t, not in the triangle hit here. Watertight's own
            // triangle comes back at t within ~3e-6 of 0 with a sign set by rounding (see
            // below), so there the groups may also differ in which triangle is hit.
            if (group != 0 && test == TriangleTest::moller)
              CHECK_MESSAGE(h.prim == oracle[0][i].prim, "origin on triangle: fused ", name(test), " ", name(isa),
                            " reports another triangle than the unfused oracle");
            // The own triangle is reported at t = 0 (plane, moller) or within 1e-6 of it.
            if (h.prim == 0) CHECK(std::fabs(h.t) <= (test == TriangleTest::watertight ? 1e-5f : 0.0f));
          }
        }
        std::size_t differ = 0;
        const std::vector<Hit>& want = oracle[group];
        for (std::size_t i = 0; i < rays.size(); ++i)
          differ += want[i].prim != a.hits[i].prim || (want[i].hit() && want[i].t != a.hits[i].t);
        CHECK_MESSAGE(differ == 0, "origin on triangle: ", name(test), " ", name(isa), " ", name(mode),
                      " differs from the single rays of ", group_name(group), " in ", differ, " rays");
      }
    MESSAGE("origin on triangle, tmin = 0, ", name(test), ": leaving ", self[leaving], " self-hits at t = 0 / ",
            other[leaving], " other / ", none[leaving], " none; entering ", self[entering], " / ", other[entering],
            " / ", none[entering], "; in plane ", self[in_plane], " / ", other[in_plane], " / ", none[in_plane]);
    // Pinned (measured 2026-11-22, the same for every ISA and mode, checked above):
    // - in-plane rays (det = 0) never hit the triangle they lie in, nor anything else here;
    // - plane and moller: every ray crossing the plane reports its own triangle at t == 0
    //   exactly (tmin <= t is inclusive);
    // - watertight: the own triangle comes back at |t| up to ~3e-6, not 0 (the shear
    //   transform rounds); where the rounded t is negative (18-21% here, leaving and entering
    //   alike) the ray passes on to the next surface. So with tmin = 0 a spawned ray may or
    //   may not re-hit its origin triangle: spawn code must offset (docs/accuracy.md).
    CHECK(self[in_plane] == 0);
    CHECK(other[in_plane] == 0);
    if (test == TriangleTest::watertight) {
      CHECK(self[leaving] > std::size_t(per / 2));
      CHECK(self[entering] > std::size_t(per / 2));
      CHECK(self[leaving] + other[leaving] == std::size_t(per));
      CHECK(self[entering] + other[entering] == std::size_t(per));
    } else {
      CHECK(self[leaving] + self[entering] == std::size_t(2 * per));
    }
  }
}

// Found by this suite (VOLLEY_STRESS_LONG=1 showed it first): rays from inside a closed cube
// aimed exactly at shared vertices and edges, where the triangles meeting there give t values
// 1-2 ulps apart: in 10-20 of 20808 rays per ISA and mode, the SIMD packet and stream
// traversals (watertight) reported a different triangle than the single ray, half of them
// the farther one. Cause: the watertight test's scaled range prefilter, t det < tmax |det|,
// rounds tmax |det| and rejected a triangle 1 ulp nearer than the current hit, so the
// answer depended on the order triangles were met in. The prefilter is now widened so that
// only the exact quotient test decides (core/triangle_watertight.h, simd/triangle/watertight.h).
TEST_CASE("stress 13: packets and streams give exactly the single-ray closest hit at shared vertices") {
  const ClosedMesh cube = grid_cube(8);
  std::size_t exact = 0, origins = 0;
  const std::vector<Ray> rays = closed_mesh_rays(cube, 0.0f, exact, origins);
  for (TriangleTest test : kTests)
    for (Isa isa : isas()) {
      const Accel accel = cube.mesh.accel(test, isa);
      std::vector<Hit> want(rays.size());
      for (std::size_t i = 0; i < rays.size(); ++i) want[i] = accel.intersect(rays[i]);
      for (Mode mode : kModes) {
        const Answers a = trace(accel, rays, mode);
        std::size_t differ = 0;
        for (std::size_t i = 0; i < rays.size(); ++i) differ += !same(a.hits[i], want[i], false);
        INFO(name(test), " ", name(isa), " ", name(mode));
        CHECK(differ == 0);
      }
    }
}
