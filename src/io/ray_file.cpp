#include "io/ray_file.h"

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

#include "io/load_error.h"
#include "io/record_file.h"

namespace volley::io {
namespace {

static_assert(sizeof(Ray) == 32 && sizeof(Hit) == 24, "records are the public structs byte for byte");

/// A version-1 .vhit record: a Hit before geometries (prim was the scene-wide id).
struct HitV1 {
  float t, u, v;
  std::uint32_t prim;
};
static_assert(sizeof(HitV1) == 16);
static_assert(sizeof(float) == 4 && std::numeric_limits<float>::is_iec559, "records hold IEEE binary32");

}  // namespace

using record_file::File;
using record_file::le32;
using record_file::read_records;
using record_file::write_records;

std::vector<Ray> read_rays(const std::filesystem::path& file) {
  return read_records<Ray>(file, "VRAY", "ray file (.vray)", "VHIT", "hit file (.vhit)", kRayFileVersion,
                           std::to_string(kRayFileVersion));
}

void write_rays(const std::filesystem::path& file, std::span<const Ray> rays) {
  write_records<Ray>(file, "VRAY", kRayFileVersion, rays, "ray file");
}

std::vector<Hit> read_hits(const std::filesystem::path& file) {
  const std::string versions = std::to_string(kHitFileVersion) + " or 1";
  // The version decides the record size; a file too short to say is left to the full read.
  unsigned char header[8] = {};
  if (File f(std::fopen(file.c_str(), "rb"), &std::fclose); f) {
    if (std::fread(header, 1, sizeof(header), f.get()) == sizeof(header) && std::memcmp(header, "VHIT", 4) == 0 &&
        le32(header + 4) == 1) {
      const std::vector<HitV1> old =
          read_records<HitV1>(file, "VHIT", "hit file (.vhit)", "VRAY", "ray file (.vray)", 1, versions);
      std::vector<Hit> hits(old.size());
      for (std::size_t i = 0; i < old.size(); ++i) {
        hits[i] = {old[i].t, old[i].u, old[i].v, old[i].prim};
        if (hits[i].hit()) hits[i].geom = 0;  // one geometry: prim ids were scene-wide
      }
      return hits;
    }
  }
  return read_records<Hit>(file, "VHIT", "hit file (.vhit)", "VRAY", "ray file (.vray)", kHitFileVersion, versions);
}

void write_hits(const std::filesystem::path& file, std::span<const Hit> hits) {
  write_records<Hit>(file, "VHIT", kHitFileVersion, hits, "hit file");
}

}  // namespace volley::io
