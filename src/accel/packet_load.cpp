// volley::load for packets of 4, 8 and 16 (volley/packet.h): a whole packet by the widest
// ISA's transposes (simd/packet_load.h), chosen once; a partial one, or any on a CPU
// without SSE4.2, lane by lane as the header's template does.
#include "simd/arch.h"
#include "simd/dispatch.h"
#include "simd/packet_load.h"
#include "volley/packet.h"

namespace volley {
namespace {

template <int K>
using WholeLoad = void (*)(RayPacket<K>&, const Ray*);

template <int K>
WholeLoad<K> widest_whole_load() {
  const Isa isa = simd::best_isa();
  if (isa == Isa::scalar) return nullptr;
  return simd::visit_arch(isa, [](auto arch) -> WholeLoad<K> { return &simd::PacketLoad<decltype(arch)>::whole; });
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

}  // namespace volley
