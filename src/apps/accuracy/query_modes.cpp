#include "accuracy/query_modes.h"

#include <algorithm>

#include "simd/isa/dispatch.h"
#include "volley/packet.h"

namespace volley::accuracy {
namespace {

constexpr Isa kSimdIsas[] = {Isa::sse42, Isa::avx2, Isa::avx512};

template <int K>
void intersect_packets(const Accel& accel, std::span<const Ray> rays, Hit* hits) {
  RayPacket<K> p;
  HitPacket<K> h;
  for (std::size_t first = 0; first < rays.size(); first += K) {
    const int count = static_cast<int>(std::min<std::size_t>(K, rays.size() - first));
    load(p, rays.data() + first, count);
    reset(h);
    accel.intersect(p, h);
    store(h, hits + first, count);
  }
}

template <int K>
void occluded_packets(const Accel& accel, std::span<const Ray> rays, Answers& out) {
  RayPacket<K> p;
  for (std::size_t first = 0; first < rays.size(); first += K) {
    const int count = static_cast<int>(std::min<std::size_t>(K, rays.size() - first));
    load(p, rays.data() + first, count);
    const std::uint32_t mask = accel.occluded(p);
    for (int i = 0; i < count; ++i) out.occluded[first + i] = (mask >> i) & 1u;
    out.inactive_lane_reports += (mask & ~lane_bits(count)) != 0u;
  }
}

}  // namespace

std::vector<Isa> available_isas() {
  std::vector<Isa> out{Isa::scalar};
  for (Isa isa : kSimdIsas)
    if (simd::cpu_has(isa)) out.push_back(isa);
  return out;
}

std::vector<Isa> missing_isas() {
  std::vector<Isa> out;
  for (Isa isa : kSimdIsas)
    if (!simd::cpu_has(isa)) out.push_back(isa);
  return out;
}

std::string name(Mode mode) {
  switch (mode) {
    case Mode::single:
      return "single";
    case Mode::packet4:
      return "packet4";
    case Mode::packet8:
      return "packet8";
    case Mode::packet16:
      return "packet16";
    case Mode::stream:
      return "stream";
  }
  return "?";
}

bool parse_mode(const std::string& text, Mode& mode) {
  for (Mode m : kModes)
    if (name(m) == text) {
      mode = m;
      return true;
    }
  return false;
}

void intersect(const Accel& accel, std::span<const Ray> rays, Mode mode, std::vector<Hit>& hits) {
  hits.resize(rays.size());
  switch (mode) {
    case Mode::single:
      for (std::size_t i = 0; i < rays.size(); ++i) hits[i] = accel.intersect(rays[i]);
      break;
    case Mode::packet4:
      intersect_packets<4>(accel, rays, hits.data());
      break;
    case Mode::packet8:
      intersect_packets<8>(accel, rays, hits.data());
      break;
    case Mode::packet16:
      intersect_packets<16>(accel, rays, hits.data());
      break;
    case Mode::stream:
      accel.intersect(rays.data(), rays.size(), hits.data(), 1);
      break;
  }
}

Answers trace(const Accel& accel, std::span<const Ray> rays, Mode mode) {
  Answers a;
  intersect(accel, rays, mode, a.hits);
  a.occluded.assign(rays.size(), 0);
  switch (mode) {
    case Mode::single:
      for (std::size_t i = 0; i < rays.size(); ++i) a.occluded[i] = accel.occluded(rays[i]) ? 1 : 0;
      break;
    case Mode::packet4:
      occluded_packets<4>(accel, rays, a);
      break;
    case Mode::packet8:
      occluded_packets<8>(accel, rays, a);
      break;
    case Mode::packet16:
      occluded_packets<16>(accel, rays, a);
      break;
    case Mode::stream:
      accel.occluded(rays.data(), rays.size(), a.occluded.data(), 1);
      break;
  }
  return a;
}

}  // namespace volley::accuracy
