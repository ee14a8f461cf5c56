#include "io/query_files.h"

#include <cstring>
#include <limits>
#include <string>
#include <type_traits>

#include "io/load_error.h"
#include "io/record_file.h"

namespace volley::io {

// Hit records go to and from the file's words by memcpy: Hit has default member values
// (so it is not trivial), but it is trivially copyable, which is all memcpy needs.
static_assert(std::is_trivially_copyable_v<Hit>);

namespace {

using record_file::read_records;
using record_file::write_records;

struct Point {
  float x, y, z;
};
static_assert(sizeof(Point) == 12);

constexpr std::uint32_t kVersion = 1;
const std::string kVersionText = "1";

}  // namespace

ClosestRecord closest_record(const ClosestPoint& c) {
  if (!c.found()) {
    const float inf = std::numeric_limits<float>::infinity();
    return {inf, inf, inf, kInvalidId, kInvalidPrim};
  }
  return {c.point[0], c.point[1], c.point[2], c.geom, c.prim};
}

std::vector<float> read_points(const std::filesystem::path& file) {
  const std::vector<Point> p = read_records<Point>(file, "VPTS", "point file (.vpts)", "VRAY", "ray file (.vray)", kVersion, kVersionText);
  std::vector<float> xyz(3 * p.size());
  for (std::size_t i = 0; i < p.size(); ++i) xyz[3 * i] = p[i].x, xyz[3 * i + 1] = p[i].y, xyz[3 * i + 2] = p[i].z;
  return xyz;
}

void write_points(const std::filesystem::path& file, std::span<const float> xyz) {
  std::vector<Point> p(xyz.size() / 3);
  for (std::size_t i = 0; i < p.size(); ++i) p[i] = {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]};
  write_records<Point>(file, "VPTS", kVersion, p, "point file");
}

std::vector<std::uint32_t> read_counts(const std::filesystem::path& file) {
  return read_records<std::uint32_t>(file, "VCNT", "count file (.vcnt)", "VHIT", "hit file (.vhit)", kVersion, kVersionText);
}
void write_counts(const std::filesystem::path& file, std::span<const std::uint32_t> counts) {
  write_records<std::uint32_t>(file, "VCNT", kVersion, counts, "count file");
}
std::vector<std::uint8_t> read_occupancy(const std::filesystem::path& file) {
  return read_records<std::uint8_t>(file, "VOCC", "occupancy file (.vocc)", "VDST", "distance file (.vdst)", kVersion, kVersionText);
}
void write_occupancy(const std::filesystem::path& file, std::span<const std::uint8_t> inside) {
  write_records<std::uint8_t>(file, "VOCC", kVersion, inside, "occupancy file");
}
std::vector<float> read_distances(const std::filesystem::path& file) {
  return read_records<float>(file, "VDST", "distance file (.vdst)", "VOCC", "occupancy file (.vocc)", kVersion, kVersionText);
}
void write_distances(const std::filesystem::path& file, std::span<const float> distances) {
  write_records<float>(file, "VDST", kVersion, distances, "distance file");
}
std::vector<ClosestRecord> read_closest(const std::filesystem::path& file) {
  return read_records<ClosestRecord>(file, "VCLP", "closest-point file (.vclp)", "VPTS", "point file (.vpts)", kVersion, kVersionText);
}
void write_closest(const std::filesystem::path& file, std::span<const ClosestRecord> points) {
  write_records<ClosestRecord>(file, "VCLP", kVersion, points, "closest-point file");
}

HitLists read_hit_lists(const std::filesystem::path& file) {
  // One u32 word stream: the header's count is the rays; offsets and hits follow. Read as
  // words, then split and check.
  const record_file::Words in = record_file::read_words(file, "VALL", "hit-list file (.vall)", kVersion);
  const std::vector<std::uint32_t>& words = in.words;
  const std::uint64_t rays = in.count;
  HitLists lists;
  if (rays >= words.size() / 2) throw LoadError(file, "truncated: the header announces " + std::to_string(rays) + " rays, but their offsets do not fit");
  lists.offsets.resize(rays + 1);
  for (std::size_t i = 0; i <= rays; ++i) lists.offsets[i] = std::uint64_t(words[2 * i]) | std::uint64_t(words[2 * i + 1]) << 32;
  const std::size_t rest = words.size() - 2 * (rays + 1);
  if (rest % 6 != 0) throw LoadError(file, "the hit records after the offsets are not whole (24 bytes each)");
  const std::size_t hits = rest / 6;
  if (lists.offsets[0] != 0 || lists.offsets[rays] != hits)
    throw LoadError(file, "offsets must run from 0 to the " + std::to_string(hits) + " hit records that follow");
  for (std::size_t i = 0; i < rays; ++i)
    if (lists.offsets[i + 1] < lists.offsets[i]) throw LoadError(file, "offset " + std::to_string(i + 1) + " is smaller than the one before");
  lists.hits.resize(hits);
  if (hits > 0) std::memcpy(static_cast<void*>(lists.hits.data()), words.data() + 2 * (rays + 1), hits * sizeof(Hit));
  return lists;
}

void write_hit_lists(const std::filesystem::path& file, const HitLists& lists) {
  std::vector<std::uint32_t> words;
  words.reserve(2 * lists.offsets.size() + 6 * lists.hits.size());
  for (std::size_t o : lists.offsets) words.insert(words.end(), {std::uint32_t(o), std::uint32_t(std::uint64_t(o) >> 32)});
  const std::size_t first = words.size();
  words.resize(first + 6 * lists.hits.size());
  if (!lists.hits.empty()) std::memcpy(words.data() + first, lists.hits.data(), lists.hits.size() * sizeof(Hit));
  write_records<std::uint32_t>(file, "VALL", kVersion, words, "hit-list file",
                               lists.offsets.empty() ? 0 : lists.offsets.size() - 1);
}

}  // namespace volley::io
