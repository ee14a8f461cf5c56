// Embedding volley from C++: a triangle, one ray, then a packet of 16 rays.
#include <volley/accel.h>

#include <cstdio>

int main() {
  const float xyz[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};  // a triangle in the plane z = 0
  const std::uint32_t indices[] = {0, 1, 2};
  try {
    volley::Accel accel;
    accel.add_triangles(xyz, 3, indices, 1);  // copied: xyz and indices may go now
    accel.commit({volley::TriangleTest::watertight, volley::Isa::automatic});

    const volley::Ray ray{{0.25f, 0.25f, 1.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, 100.0f};  // org, tmin, dir, tmax
    const volley::Hit hit = accel.intersect(ray);
    std::printf("t = %g, prim = %u, u = %g, v = %g\n", hit.t, hit.prim, hit.u, hit.v);

    volley::Ray rays[16];  // a row of rays at y = 0.1: the first 14 hit
    for (int i = 0; i < 16; ++i) rays[i] = {{(i + 0.5f) / 16, 0.1f, 1.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, 100.0f};
    volley::RayPacket<16> packet;  // SoA, 64-byte aligned
    volley::HitPacket<16> hits;
    volley::load(packet, rays, 16);  // AoS to SoA: the library's transposes for whole packets
    volley::reset(hits);  // t = +inf: search the whole interval
    accel.intersect(packet, hits);
    int hit_count = 0;
    for (int i = 0; i < 16; ++i) hit_count += hits.prim[i] != volley::kInvalidPrim;
    std::printf("%d of 16 packet rays hit\n", hit_count);
    return hit.prim == 0 && hit.t == 1.0f && hit_count == 14 ? 0 : 1;
  } catch (const volley::Error& e) {  // invalid input, or no commit before a query
    std::fprintf(stderr, "volley: %s\n", e.what());
    return 1;
  }
}
