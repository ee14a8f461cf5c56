// Ray files (.vray) and hit files (.vhit): the rays `volley rays` writes and `volley trace`
// reads, and the answers `volley trace -o` writes. Formats (README, "Tracing ray files"), little-endian:
//
//   .vray  "VRAY"  u32 version = 1  u64 count  count x { f32 ox oy oz tmin dx dy dz tmax }   32 B
//   .vhit  "VHIT"  u32 version = 2  u64 count  count x { f32 t u v; u32 prim geom inst }      24 B
//          (version 1, still read: { f32 t u v; u32 prim } 16 B, prim scene-wide: geom 0)
//
// The 16-byte header is followed by exactly count records; nothing may follow them.
#pragma once
#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

#include "volley/ray.h"

namespace volley::io {

/// Bytes before the first record of either file: magic (4), version (4), count (8).
inline constexpr std::size_t kRayFileHeaderBytes = 16;
/// The version of .vray files.
inline constexpr std::uint32_t kRayFileVersion = 1;
/// The version .vhit files are written in (Hit with geom and inst); version 1 is read too.
inline constexpr std::uint32_t kHitFileVersion = 2;

/// Reads a .vray file. Throws LoadError (`FILE: ...`) when the file is missing or
/// unreadable, does not start with "VRAY" (a .vhit file is named as such), has another
/// version, is shorter than its header, or when its size does not match the count in the
/// header (truncated records, trailing bytes, or a count no file could hold).
/// Safe to call from several threads at once.
std::vector<Ray> read_rays(const std::filesystem::path& file);

/// Writes `rays` as a .vray file, replacing any file there and creating the parent folder
/// when missing. Throws std::runtime_error (`FILE: cannot write ray file (...)`).
void write_rays(const std::filesystem::path& file, std::span<const Ray> rays);

/// Reads a .vhit file, version 2 or 1 (a version-1 hit reads as geometry 0, no instance);
/// the same checks and errors as read_rays with "VHIT" records.
std::vector<Hit> read_hits(const std::filesystem::path& file);

/// Writes `hits` as a .vhit file (as write_rays). A miss is t = +inf, prim = kInvalidPrim.
void write_hits(const std::filesystem::path& file, std::span<const Hit> hits);

/// The .vhit record of an occlusion answer: blocked is t = 0, u = v = 0, prim = geom = 0
/// (an any-hit query does not say which primitive blocked, but Hit::hit() is true);
/// unblocked is a miss (t = +inf, prim = kInvalidPrim).
inline Hit occlusion_record(bool blocked) {
  Hit h;
  if (blocked) {
    h.t = 0.0f;
    h.prim = 0;
    h.geom = 0;
  }
  return h;
}

}  // namespace volley::io
