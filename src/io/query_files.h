// The files of the queries beyond the first hit (`volley trace --count/--all`, `volley
// query`), in .vray's scheme (io/record_file.h): 4-byte magic, u32 version = 1, u64
// count, then one little-endian record per ray or point (README, "Queries beyond the first hit"):
//
//   .vpts  "VPTS"  count x { f32 x y z }                          12 B  query points
//   .vcnt  "VCNT"  count x { u32 crossings }                       4 B  per ray
//   .vocc  "VOCC"  count x { u8 inside }                           1 B  per point (1 = inside)
//   .vdst  "VDST"  count x { f32 distance }                        4 B  per point (signed: negative inside)
//   .vclp  "VCLP"  count x { f32 x y z; u32 geometry primitive }  20 B  per point (a miss: +inf, ~0u)
//   .vall  "VALL"  count = rays; then (count + 1) x u64 offsets, then offsets[count] .vhit
//                  records (24 B): ray i's hits are records offsets[i] .. offsets[i + 1], nearest first
#pragma once
#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

#include "volley/point.h"
#include "volley/ray.h"

namespace volley::io {

/// A .vclp record.
struct ClosestRecord {
  float x, y, z;
  std::uint32_t geometry, primitive;
};
static_assert(sizeof(ClosestRecord) == 20);
/// The record of a ClosestPoint (a miss: x = y = z = +inf, ids ~0u).
ClosestRecord closest_record(const ClosestPoint& c);

/// Reads a .vpts file: 3 floats per point. Throws LoadError naming the file and the fault
/// (missing, another magic, version or size), as read_rays does.
std::vector<float> read_points(const std::filesystem::path& file);
void write_points(const std::filesystem::path& file, std::span<const float> xyz);

std::vector<std::uint32_t> read_counts(const std::filesystem::path& file);
void write_counts(const std::filesystem::path& file, std::span<const std::uint32_t> counts);
std::vector<std::uint8_t> read_occupancy(const std::filesystem::path& file);
void write_occupancy(const std::filesystem::path& file, std::span<const std::uint8_t> inside);
std::vector<float> read_distances(const std::filesystem::path& file);
void write_distances(const std::filesystem::path& file, std::span<const float> distances);
std::vector<ClosestRecord> read_closest(const std::filesystem::path& file);
void write_closest(const std::filesystem::path& file, std::span<const ClosestRecord> points);

/// .vall: the offsets and hits of HitLists. read_hit_lists also checks that the offsets
/// start at 0, never decrease and end at the number of hit records that follow.
HitLists read_hit_lists(const std::filesystem::path& file);
void write_hit_lists(const std::filesystem::path& file, const HitLists& lists);

}  // namespace volley::io
