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

using File = std::unique_ptr<std::FILE, int (*)(std::FILE*)>;

// Both formats are little-endian; records are 32-bit words (f32 or u32), so on a
// big-endian host swapping each word converts a whole record in place.
void to_from_little_endian(void* words, std::size_t count) {
  if constexpr (std::endian::native == std::endian::big) {
    auto* w = static_cast<std::uint32_t*>(words);
    for (std::size_t i = 0; i < count; ++i)
      w[i] = (w[i] >> 24) | ((w[i] >> 8) & 0xff00u) | ((w[i] << 8) & 0xff0000u) | (w[i] << 24);
  } else {
    (void)words;
    (void)count;
  }
}

std::uint32_t le32(const unsigned char* b) {
  return std::uint32_t(b[0]) | std::uint32_t(b[1]) << 8 | std::uint32_t(b[2]) << 16 | std::uint32_t(b[3]) << 24;
}

std::uint64_t le64(const unsigned char* b) { return std::uint64_t(le32(b)) | std::uint64_t(le32(b + 4)) << 32; }

void put_le32(unsigned char* b, std::uint32_t x) {
  for (int i = 0; i < 4; ++i) b[i] = static_cast<unsigned char>(x >> (8 * i));
}

// A printable rendering of 4 magic bytes: "VRAY", or \xNN escapes.
std::string quote_magic(const unsigned char* m) {
  std::string s = "\"";
  for (int i = 0; i < 4; ++i) {
    if (m[i] >= 0x20 && m[i] < 0x7f && m[i] != '"' && m[i] != '\\') {
      s += char(m[i]);
    } else {
      char buf[8];
      std::snprintf(buf, sizeof(buf), "\\x%02x", m[i]);
      s += buf;
    }
  }
  return s + "\"";
}

// Reads header and records of one format into `out` (Record = Ray or Hit).
template <class Record>
std::vector<Record> read_records(const std::filesystem::path& file, const char magic[4], const char* what,
                                 const char* other_magic, const char* other_what, std::uint32_t want_version,
                                 const std::string& versions) {
  std::error_code ec;
  const auto status = std::filesystem::status(file, ec);
  if (!std::filesystem::exists(status)) throw LoadError(file, "file not found");
  if (std::filesystem::is_directory(status)) throw LoadError(file, "is a directory, expected a " + std::string(what));
  File f(std::fopen(file.c_str(), "rb"), &std::fclose);
  if (!f) throw LoadError(file, std::string("cannot open file (") + std::strerror(errno) + ")");
  const std::uintmax_t size = std::filesystem::file_size(file, ec);
  if (ec) throw LoadError(file, "cannot read file size (" + ec.message() + ")");

  unsigned char header[kRayFileHeaderBytes];
  const std::size_t got = std::fread(header, 1, sizeof(header), f.get());
  if (got >= 4 && std::memcmp(header, magic, 4) != 0) {
    std::string msg = "not a " + std::string(what) + ": expected magic \"" + std::string(magic, 4) +
                      "\" at byte 0, found " + quote_magic(header);
    if (std::memcmp(header, other_magic, 4) == 0) msg += " (this is a " + std::string(other_what) + ")";
    throw LoadError(file, msg);
  }
  if (got < sizeof(header))
    throw LoadError(file, "truncated header: " + std::to_string(got) + " bytes, expected " +
                              std::to_string(kRayFileHeaderBytes) + " (magic, u32 version, u64 count)");
  const std::uint32_t version = le32(header + 4);
  if (version != want_version)
    throw LoadError(file, "unsupported " + std::string(what) + " version " + std::to_string(version) + " (expected " +
                              versions + ")");
  const std::uint64_t count = le64(header + 8);
  const std::uintmax_t payload = size - kRayFileHeaderBytes;
  if (count > payload / sizeof(Record))
    throw LoadError(file, "truncated: header says " + std::to_string(count) + " records of " +
                              std::to_string(sizeof(Record)) + " bytes, but only " + std::to_string(payload) +
                              " bytes follow the header (room for " + std::to_string(payload / sizeof(Record)) + ")");
  if (payload != count * sizeof(Record))
    throw LoadError(file, std::to_string(payload - count * sizeof(Record)) + " unexpected bytes after the " +
                              std::to_string(count) + " records the header announces");

  std::vector<Record> records(count);
  if (count > 0 && std::fread(records.data(), sizeof(Record), count, f.get()) != count)
    throw LoadError(file, std::string("cannot read records (") +
                              (std::ferror(f.get()) ? std::strerror(errno) : "file shrank while reading") + ")");
  to_from_little_endian(records.data(), count * sizeof(Record) / 4);
  return records;
}

template <class Record>
void write_records(const std::filesystem::path& file, const char magic[4], std::uint32_t version,
                   std::span<const Record> records, const char* what) {
  auto fail = [&](const std::string& why) {
    throw std::runtime_error(file.string() + ": cannot write " + what + " (" + why + ")");
  };
  if (file.has_parent_path()) {
    std::error_code ec;
    std::filesystem::create_directories(file.parent_path(), ec);
    if (ec) fail(ec.message());
  }
  File f(std::fopen(file.c_str(), "wb"), &std::fclose);
  if (!f) fail(std::strerror(errno));
  unsigned char header[kRayFileHeaderBytes];
  std::memcpy(header, magic, 4);
  put_le32(header + 4, version);
  put_le32(header + 8, static_cast<std::uint32_t>(records.size()));
  put_le32(header + 12, static_cast<std::uint32_t>(std::uint64_t(records.size()) >> 32));
  bool ok = std::fwrite(header, 1, sizeof(header), f.get()) == sizeof(header);
  if constexpr (std::endian::native == std::endian::little) {
    ok = ok && (records.empty() || std::fwrite(records.data(), sizeof(Record), records.size(), f.get()) == records.size());
  } else {
    // Convert in chunks so that the caller's records stay untouched.
    std::vector<Record> chunk;
    for (std::size_t i = 0; ok && i < records.size(); i += 4096) {
      chunk.assign(records.begin() + i, records.begin() + std::min(records.size(), i + 4096));
      to_from_little_endian(chunk.data(), chunk.size() * sizeof(Record) / 4);
      ok = std::fwrite(chunk.data(), sizeof(Record), chunk.size(), f.get()) == chunk.size();
    }
  }
  if (!ok) fail(std::strerror(errno));
  if (std::fclose(f.release()) != 0) fail(std::strerror(errno));
}

}  // namespace

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
