// volley::load for packets of 4, 8 and 16 (and the library's double packets of 32) and
// volley::store for packets of 16 (volley/packet.h): whole packets by the widest ISA's
// transposes (simd/rays/packet_convert.h), chosen once; partial ones, or any on a CPU without
// them, lane by lane as the header's templates do.
#include "accel/wide/wide_accel.h"
#include "simd/isa/arch.h"
#include "simd/isa/dispatch.h"
#include "simd/rays/packet_convert.h"
#include "volley/packet.h"

namespace volley {
namespace {

template <int K>
using WholeLoad = void (*)(RayPacket<K>&, const Ray*);
using WholeStore = void (*)(const HitPacket<16>&, Hit*);

template <int K>
WholeLoad<K> widest_whole_load() {
  const Isa isa = simd::best_isa();
  if (isa == Isa::scalar) return nullptr;
  return simd::visit_arch(isa, [](auto arch) -> WholeLoad<K> { return &simd::PacketConvert<decltype(arch)>::whole; });
}

WholeStore widest_whole_store() {
  const Isa isa = simd::best_isa();
  if (isa == Isa::scalar) return nullptr;
  return simd::visit_arch(isa, [](auto arch) -> WholeStore {
    using Convert = simd::PacketConvert<decltype(arch)>;
    return Convert::kStore ? &Convert::store : nullptr;
  });
}

template <int K>
void load_lanes(RayPacket<K>& packet, const Ray* rays, int count) {
  static const WholeLoad<K> whole = widest_whole_load<K>();
  if (count >= K && whole != nullptr)
    whole(packet, rays);
  else
    load<K>(packet, rays, count);
}

}  // namespace

void load(RayPacket<16>& packet, const Ray* rays, int count) {
  load_lanes(packet, rays, count);
}
void load(RayPacket<8>& packet, const Ray* rays, int count) {
  load_lanes(packet, rays, count);
}
void load(RayPacket<4>& packet, const Ray* rays, int count) {
  load_lanes(packet, rays, count);
}
void load(RayPacket<32>& packet, const Ray* rays, int count) {
  load_lanes(packet, rays, count);
}

void store(const HitPacket<16>& hits, Hit* out, int count) {
  static const WholeStore whole = widest_whole_store();
  if (count >= 16 && whole != nullptr)
    whole(hits, out);
  else
    store<16>(hits, out, count);
}

}  // namespace volley
