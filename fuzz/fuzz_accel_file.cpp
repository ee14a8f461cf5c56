// libFuzzer target: Accel::load on untrusted structure files. The fuzzer's bytes are the
// file padded with zeros to whole stripes after the header, with its size and checksum
// fields rewritten to match: else nearly every mutation (most change the size) would stop
// at the size or checksum check, which the unit tests cover. Every check behind them must
// end in volley::Error, and a file that loads must answer queries (single rays, packets,
// a stream) and commit again without a fault.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "accel/accel_file.h"
#include "fuzz_file.h"
#include "volley/accel.h"

namespace {

void query(const volley::Accel& accel) {
  std::vector<volley::Ray> rays;
  for (int i = 0; i < 48; ++i) {
    const float a = 0.37f * float(i), b = 0.11f * float(i);
    rays.push_back({{0.1f * float(i % 7) - 0.3f, 0.2f, 3.0f}, 0.0f, {std::sin(a), std::cos(a) * std::sin(b), -1.0f}, 1e30f});
  }
  for (const volley::Ray& r : rays) {
    (void)accel.intersect(r);
    (void)accel.occluded(r);
  }
  volley::RayPacket<16> packet;
  volley::HitPacket<16> hits;
  volley::load(packet, rays.data(), 16);
  volley::reset(hits);
  accel.intersect(packet, hits);
  (void)accel.occluded(packet);
  std::vector<volley::Hit> out(rays.size());
  accel.intersect(rays.data(), rays.size(), out.data());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  namespace file = volley::accel::file;
  std::vector<std::uint8_t> bytes(data, data + size);
  if (size >= file::kHeaderBytes) {
    const std::size_t stripes = (size - file::kHeaderBytes + file::kStripe - 1) / file::kStripe;
    bytes.resize(file::kHeaderBytes + stripes * file::kStripe, 0);
    const std::uint64_t total = bytes.size();
    std::memcpy(bytes.data() + offsetof(file::Header, bytes), &total, 8);
    file::Checksum sum;
    sum.add(bytes.data() + file::kHeaderBytes, bytes.size() - file::kHeaderBytes);
    const std::uint64_t value = sum.value();
    std::memcpy(bytes.data() + offsetof(file::Header, checksum), &value, 8);
  }
  const auto path = volley_fuzz::write_input("in.vacc", bytes.data(), bytes.size());
  try {
    volley::Accel accel = volley::Accel::load(path);
    query(accel);
    accel.commit();
    query(accel);
  } catch (const volley::Error&) {
  }
  return 0;
}
