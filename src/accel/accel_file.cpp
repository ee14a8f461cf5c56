#include "accel/accel_file.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <utility>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "volley/accel.h"

namespace volley::accel::file {
namespace {

constexpr std::size_t padded(std::size_t bytes) { return (bytes + kStripe - 1) / kStripe * kStripe; }

/// The header of one chunk: its tag and payload size, padded to a stripe.
struct ChunkHeader {
  std::uint32_t tag;
  std::uint32_t zero;
  std::uint64_t bytes;
  unsigned char pad[kStripe - 16];
};
static_assert(sizeof(ChunkHeader) == kStripe);

std::string system_error() { return std::strerror(errno); }

}  // namespace

void Checksum::add(const void* data, std::size_t bytes) {
  const unsigned char* p = static_cast<const unsigned char*>(data);
  for (std::size_t at = 0; at < bytes; at += kStripe) {
    std::uint64_t w[8];
    std::memcpy(w, p + at, kStripe);
    for (int l = 0; l < 8; ++l) {
      sum_[l] += w[l];
      sum2_[l] += sum_[l];
    }
  }
  stripes_ += bytes / kStripe;
}

std::uint64_t Checksum::value() const {
  // A 64-bit finaliser (multiply, xor-shift) over the lanes and the length.
  std::uint64_t h = stripes_ * 0x9E3779B97F4A7C15ull;
  auto mix = [&h](std::uint64_t x) {
    h = (h ^ x) * 0xBF58476D1CE4E5B9ull;
    h ^= h >> 31;
    h *= 0x94D049BB133111EBull;
    h ^= h >> 29;
  };
  for (int l = 0; l < 8; ++l) {
    mix(sum_[l]);
    mix(sum2_[l]);
  }
  return h;
}

Writer::Writer(std::string path) : path_(std::move(path)), temp_(path_ + ".tmp") {
  out_ = std::fopen(temp_.c_str(), "wb");
  if (!out_) throw Error("save: cannot write " + temp_ + ": " + system_error());
  const unsigned char zeros[kHeaderBytes] = {};
  write(zeros, kHeaderBytes);  // the header comes last, over these
}

Writer::~Writer() {
  if (!out_) return;
  std::fclose(out_);  // an unfinished save: no partial file stays behind
  std::remove(temp_.c_str());
}

void Writer::write(const void* data, std::size_t bytes) {
  if (bytes != 0 && std::fwrite(data, 1, bytes, out_) != bytes)
    throw Error("save: writing " + temp_ + " failed: " + system_error());
  offset_ += bytes;
}

void Writer::chunk(Tag tag, const void* data, std::size_t bytes) {
  ChunkHeader head{};
  head.tag = static_cast<std::uint32_t>(tag);
  head.bytes = bytes;
  write(&head, sizeof head);
  sum_.add(&head, sizeof head);
  const std::size_t whole = bytes / kStripe * kStripe;
  write(data, bytes);
  sum_.add(data, whole);
  unsigned char tail[kStripe] = {};
  if (bytes != whole) {
    std::memcpy(tail, static_cast<const unsigned char*>(data) + whole, bytes - whole);
    write(tail + (bytes - whole), kStripe - (bytes - whole));
    sum_.add(tail, kStripe);
  }
}

void Writer::finish(Header header) {
  std::memcpy(header.magic, kMagic, sizeof kMagic);
  header.version = kVersion;
  header.byte_order = kByteOrder;
  header.bytes = offset_;
  header.checksum = sum_.value();
  unsigned char bytes[kHeaderBytes] = {};
  std::memcpy(bytes, &header, sizeof header);
  if (std::fseek(out_, 0, SEEK_SET) != 0 || std::fwrite(bytes, 1, kHeaderBytes, out_) != kHeaderBytes ||
      std::fflush(out_) != 0)
    throw Error("save: writing " + temp_ + " failed: " + system_error());
  const int closed = std::fclose(out_);
  out_ = nullptr;
  if (closed != 0 || std::rename(temp_.c_str(), path_.c_str()) != 0) {
    const std::string why = system_error();
    std::remove(temp_.c_str());
    throw Error("save: cannot write " + path_ + ": " + why);
  }
}

Mapping::Mapping(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw Error("load: cannot open " + path + ": " + system_error());
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    throw Error("load: " + path + " is not a regular file");
  }
  size_ = static_cast<std::size_t>(st.st_size);
  if (size_ != 0) {
    // Populated up front: the checksum reads every page next anyway.
    void* p = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0);
    if (p == MAP_FAILED) {
      const std::string why = system_error();
      ::close(fd);
      throw Error("load: cannot map " + path + ": " + why);
    }
    data_ = static_cast<const unsigned char*>(p);
  }
  ::close(fd);
}

Mapping::~Mapping() {
  if (data_) ::munmap(const_cast<unsigned char*>(data_), size_);
}

Reader::Reader(std::shared_ptr<const Mapping> map, std::string path) : map_(std::move(map)), path_(std::move(path)) {
  const std::size_t size = map_->size();
  finished_ = true;  // header faults are reported as they are: nothing to sum yet
  if (size < kHeaderBytes || std::memcmp(map_->data(), kMagic, sizeof kMagic) != 0)
    fail("not a volley structure file (it does not start with \"VOLLEYAC\"; write one with Accel::save or "
         "volley trace --save)");
  std::memcpy(&header_, map_->data(), sizeof header_);
  if (header_.byte_order != kByteOrder) fail("written on a machine of the other byte order");
  if (header_.version != kVersion)
    fail("format version " + std::to_string(header_.version) + "; this build of volley reads version " +
         std::to_string(kVersion) + " (build the structure again and save it)");
  if (header_.bytes != size)
    fail("truncated or extended: the header says " + std::to_string(header_.bytes) + " bytes, the file has " +
         std::to_string(size));
  if ((size - kHeaderBytes) % kStripe != 0) fail("its size is not a whole number of 64-byte chunks");
  finished_ = false;
}

void Reader::sum_to(std::size_t end) {
  sum_.add(map_->data() + summed_, end - summed_);
  summed_ = end;
}

std::span<const unsigned char> Reader::next_raw(Tag tag, std::size_t item_bytes, SlabCheck check) {
  const std::size_t size = map_->size();
  const std::string name = "chunk " + std::to_string(static_cast<unsigned>(tag));
  if (size - offset_ < sizeof(ChunkHeader)) fail(name + " is missing (the file ends early)");
  ChunkHeader head;
  std::memcpy(&head, map_->data() + offset_, sizeof head);
  if (head.tag != static_cast<std::uint32_t>(tag))
    fail("expected " + name + " at byte " + std::to_string(offset_) + ", found chunk " + std::to_string(head.tag));
  offset_ += sizeof head;
  sum_to(offset_);
  if (head.bytes > size - offset_ || padded(head.bytes) > size - offset_)
    fail(name + " claims " + std::to_string(head.bytes) + " bytes, past the end of the file");
  if (head.bytes % item_bytes != 0)
    fail(name + " holds " + std::to_string(head.bytes) + " bytes, not a whole number of " +
         std::to_string(item_bytes) + "-byte items");
  const unsigned char* data = map_->data() + offset_;
  // Slabs of whole items and whole stripes, about 64 KiB: summed, then checked in cache.
  const std::size_t unit = item_bytes * kStripe;
  const std::size_t slab = std::max<std::size_t>(1, (std::size_t{1} << 16) / unit) * unit;
  for (std::size_t at = 0; at < head.bytes; at += slab) {
    const std::size_t n = std::min(slab, static_cast<std::size_t>(head.bytes) - at);
    sum_to(offset_ + at + padded(n));
    check.call(check.context, {data + at, n});
  }
  offset_ += padded(head.bytes);
  sum_to(offset_);
  return {data, static_cast<std::size_t>(head.bytes)};
}

void Reader::finish() {
  if (offset_ != map_->size()) fail("unexpected bytes after the last chunk");
  sum_to(offset_);
  finished_ = true;
  if (sum_.value() != header_.checksum) fail("checksum mismatch: the file is corrupted");
}

void Reader::fail(const std::string& what) {
  if (!finished_) {
    finished_ = true;
    sum_to(map_->size());
    if (sum_.value() != header_.checksum) throw Error("load: " + path_ + ": checksum mismatch: the file is corrupted");
  }
  throw Error("load: " + path_ + ": " + what);
}

}  // namespace volley::accel::file
