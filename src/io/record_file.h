// The scheme every volley binary file shares (.vray, .vhit and the query files): 4-byte
// magic, u32 version, u64 count, then exactly count little-endian records of 32-bit words
// (or bytes). Internal to io/.
#pragma once
#include <algorithm>
#include <bit>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/load_error.h"

namespace volley::io {

/// Bytes before the first record: magic (4), version (4), count (8).
inline constexpr std::size_t kRecordHeaderBytes = 16;

namespace record_file {

using File = std::unique_ptr<std::FILE, int (*)(std::FILE*)>;

// Both formats are little-endian; records are 32-bit words (f32 or u32), so on a
// big-endian host swapping each word converts a whole record in place.
inline void to_from_little_endian(void* words, std::size_t count) {
  if constexpr (std::endian::native == std::endian::big) {
    auto* w = static_cast<std::uint32_t*>(words);
    for (std::size_t i = 0; i < count; ++i)
      w[i] = (w[i] >> 24) | ((w[i] >> 8) & 0xff00u) | ((w[i] << 8) & 0xff0000u) | (w[i] << 24);
  } else {
    (void)words;
    (void)count;
  }
}

inline std::uint32_t le32(const unsigned char* b) {
  return std::uint32_t(b[0]) | std::uint32_t(b[1]) << 8 | std::uint32_t(b[2]) << 16 | std::uint32_t(b[3]) << 24;
}

inline std::uint64_t le64(const unsigned char* b) { return std::uint64_t(le32(b)) | std::uint64_t(le32(b + 4)) << 32; }

inline void put_le32(unsigned char* b, std::uint32_t x) {
  for (int i = 0; i < 4; ++i) b[i] = static_cast<unsigned char>(x >> (8 * i));
}

// A printable rendering of 4 magic bytes: "VRAY", or \xNN escapes.
inline std::string quote_magic(const unsigned char* m) {
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

/// An opened file of the scheme, its header checked: the stream after the header, the
/// file's size and the header's count.
struct Opened {
  File f{nullptr, &std::fclose};
  std::uintmax_t size = 0;
  std::uint64_t count = 0;
};

/// Opens `file` and checks its magic (naming `other_what` when it has `other_magic`) and version.
inline Opened open_file(const std::filesystem::path& file, const char magic[4], const char* what,
                        const char* other_magic, const char* other_what, std::uint32_t want_version,
                        const std::string& versions) {
  std::error_code ec;
  const auto status = std::filesystem::status(file, ec);
  if (!std::filesystem::exists(status)) throw LoadError(file, "file not found");
  if (std::filesystem::is_directory(status)) throw LoadError(file, "is a directory, expected a " + std::string(what));
  Opened o;
  o.f.reset(std::fopen(file.c_str(), "rb"));
  if (!o.f) throw LoadError(file, std::string("cannot open file (") + std::strerror(errno) + ")");
  o.size = std::filesystem::file_size(file, ec);
  if (ec) throw LoadError(file, "cannot read file size (" + ec.message() + ")");

  unsigned char header[kRecordHeaderBytes];
  const std::size_t got = std::fread(header, 1, sizeof(header), o.f.get());
  if (got >= 4 && std::memcmp(header, magic, 4) != 0) {
    std::string msg = "not a " + std::string(what) + ": expected magic \"" + std::string(magic, 4) +
                      "\" at byte 0, found " + quote_magic(header);
    if (std::memcmp(header, other_magic, 4) == 0) msg += " (this is a " + std::string(other_what) + ")";
    throw LoadError(file, msg);
  }
  if (got < sizeof(header))
    throw LoadError(file, "truncated header: " + std::to_string(got) + " bytes, expected " +
                              std::to_string(kRecordHeaderBytes) + " (magic, u32 version, u64 count)");
  const std::uint32_t version = le32(header + 4);
  if (version != want_version)
    throw LoadError(file, "unsupported " + std::string(what) + " version " + std::to_string(version) + " (expected " +
                              versions + ")");
  o.count = le64(header + 8);
  return o;
}

/// Reads a file of one format: checks magic, version and size against count records.
template <class Record>
std::vector<Record> read_records(const std::filesystem::path& file, const char magic[4], const char* what,
                                 const char* other_magic, const char* other_what, std::uint32_t want_version,
                                 const std::string& versions) {
  Opened o = open_file(file, magic, what, other_magic, other_what, want_version, versions);
  File& f = o.f;
  const std::uintmax_t size = o.size;
  const std::uint64_t count = o.count;
  const std::uintmax_t payload = size - kRecordHeaderBytes;
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
  if constexpr (sizeof(Record) % 4 == 0) to_from_little_endian(records.data(), count * sizeof(Record) / 4);
  return records;
}

/// Writes a file of one format: the header (count = the records, or `header_count` when
/// given: .vall), then the records.
template <class Record>
void write_records(const std::filesystem::path& file, const char magic[4], std::uint32_t version,
                   std::span<const Record> records, const char* what, std::optional<std::uint64_t> header_count = {}) {
  const std::uint64_t count = header_count.value_or(records.size());
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
  unsigned char header[kRecordHeaderBytes];
  std::memcpy(header, magic, 4);
  put_le32(header + 4, version);
  put_le32(header + 8, static_cast<std::uint32_t>(count));
  put_le32(header + 12, static_cast<std::uint32_t>(count >> 32));
  bool ok = std::fwrite(header, 1, sizeof(header), f.get()) == sizeof(header);
  if constexpr (std::endian::native == std::endian::little) {
    ok = ok && (records.empty() || std::fwrite(records.data(), sizeof(Record), records.size(), f.get()) == records.size());
  } else {
    // Convert in chunks so that the caller's records stay untouched.
    std::vector<Record> chunk;
    for (std::size_t i = 0; ok && i < records.size(); i += 4096) {
      chunk.assign(records.begin() + i, records.begin() + std::min(records.size(), i + 4096));
      if constexpr (sizeof(Record) % 4 == 0) to_from_little_endian(chunk.data(), chunk.size() * sizeof(Record) / 4);
      ok = std::fwrite(chunk.data(), sizeof(Record), chunk.size(), f.get()) == chunk.size();
    }
  }
  if (!ok) fail(std::strerror(errno));
  if (std::fclose(f.release()) != 0) fail(std::strerror(errno));
}

/// A file of the scheme whose header count does not count its records (.vall): the count
/// and every 32-bit word after the header (the caller splits and checks them).
struct Words {
  std::uint64_t count;
  std::vector<std::uint32_t> words;
};
inline Words read_words(const std::filesystem::path& file, const char magic[4], const char* what, std::uint32_t version) {
  Opened o = open_file(file, magic, what, magic, what, version, std::to_string(version));
  if ((o.size - kRecordHeaderBytes) % 4 != 0) throw LoadError(file, "the data after the header is not whole 32-bit words");
  Words out{o.count, std::vector<std::uint32_t>((o.size - kRecordHeaderBytes) / 4)};
  if (!out.words.empty() && std::fread(out.words.data(), 4, out.words.size(), o.f.get()) != out.words.size())
    throw LoadError(file, "cannot read the data (file shrank while reading)");
  to_from_little_endian(out.words.data(), out.words.size());
  return out;
}

}  // namespace record_file

}  // namespace volley::io
