// The file of a committed Accel (Accel::save, Accel::load; docs/accel-file.md): a 64-byte
// header, then tagged chunks, each a 64-byte chunk header and a payload padded to 64 bytes.
// Everything after the header is thus whole 64-byte stripes, summed by one checksum, and
// every payload is 64-byte aligned in the mapped file: the wide BVH's nodes and triangle
// blocks are queried where they lie, without a copy.
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

namespace volley::accel::file {

/// The format version this build writes and reads.
inline constexpr std::uint32_t kVersion = 1;
/// The first 8 bytes of every file.
inline constexpr char kMagic[8] = {'V', 'O', 'L', 'L', 'E', 'Y', 'A', 'C'};
/// Written as is: read back in another byte order it is 0x04030201.
inline constexpr std::uint32_t kByteOrder = 0x01020304u;

/// The chunks, in the order they are written: the scene's, then per layer (one per
/// geometry mask) a layer record, its nodes and its blocks.
enum class Tag : std::uint32_t {
  meta = 1,          ///< Meta
  geometries,        ///< one GeometryRecord per geometry
  vertices,          ///< the triangle geometries' vertices, 3 floats each, geometry after geometry
  indices,           ///< their vertex indices, 3 per triangle
  polygon_sizes,     ///< vertices per polygon geometry
  polygon_vertices,  ///< their vertices, 3 floats each
  excluded_flat,     ///< one byte per triangle: left out of the BVHs as degenerate
  layer,             ///< LayerRecord
  nodes,             ///< the layer's wide BVH nodes (none for a scalar commit)
  blocks,            ///< its triangle blocks
};

struct Header {
  char magic[8];
  std::uint32_t version;
  std::uint32_t byte_order;
  std::uint64_t bytes;     ///< the whole file
  std::uint64_t checksum;  ///< of every byte after the header
  std::uint32_t test;      ///< TriangleTest the structure answers with
  std::uint32_t isa;       ///< Isa it was built for (its kernels and block layout)
  std::uint32_t robust;
  std::uint32_t reference_double;
  std::uint32_t node_bytes;   ///< sizeof one wide node; 0 without a wide BVH
  std::uint32_t block_bytes;  ///< sizeof one triangle block; 0 without a wide BVH
};
static_assert(sizeof(Header) == 56, "the header is padded to 64 bytes in the file");
inline constexpr std::size_t kHeaderBytes = 64;
inline constexpr std::size_t kStripe = 64;

/// The meta chunk: the committed state beside the structure.
struct Meta {
  std::uint64_t geometries, triangles, polygons, next_id;
  std::uint64_t degenerate, disabled, layers;
  double build_seconds;
  std::uint32_t refitted;
  std::uint32_t quality;  ///< BuildQuality (0, medium, in files written before it was recorded)
};

/// One geometry (Accel::Impl::Geometry without its indices, which are in the indices chunk).
struct GeometryRecord {
  std::uint32_t first, count;
  std::uint64_t index, vertex_count;
  std::uint32_t polygon, enabled, moved, mask;
};
static_assert(sizeof(GeometryRecord) == 40);

/// One layer (Accel::Impl::Layer): its mask, the wide root and the statistics info() reports.
struct LayerRecord {
  std::uint32_t mask, root;
  std::uint32_t has_triangles, zero;
  double built_sah, sah_now;
  std::uint64_t bvh_nodes, bvh_leaves, bvh_depth, bvh_bytes;  ///< the binary BVH's statistics
  double bvh_sah_cost, bvh_mean_leaf_size;
  std::uint64_t wide_nodes, wide_leaves, wide_depth, wide_blocks, wide_triangles, wide_bytes;
  double wide_mean_children, wide_sah_cost, wide_block_sah_cost;
};

/// The running checksum of whole 64-byte stripes: eight lanes of 64-bit words, each with
/// its sum and its sum of sums (Fletcher's two orders: a changed, swapped or moved word
/// changes one of them), mixed at the end. Streams at memory speed (the load's cost).
class Checksum {
 public:
  /// Adds `bytes` (a multiple of kStripe) from `data`.
  void add(const void* data, std::size_t bytes);
  std::uint64_t value() const;

 private:
  std::uint64_t sum_[8] = {};
  std::uint64_t sum2_[8] = {};
  std::uint64_t stripes_ = 0;
};

/// Writes a file chunk by chunk to `path`.tmp and, at finish(), moves it to `path`: a save
/// that fails leaves no partial file under `path`. Throws Error naming the path.
class Writer {
 public:
  explicit Writer(std::string path);
  ~Writer();
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;
  /// Appends a chunk of `bytes` bytes.
  void chunk(Tag tag, const void* data, std::size_t bytes);
  template <class T>
  void chunk(Tag tag, std::span<const T> items) {
    chunk(tag, items.data(), items.size_bytes());
  }
  /// Completes `header` (magic, version, byte order, size, checksum), writes it, closes.
  void finish(Header header);

 private:
  void write(const void* data, std::size_t bytes);
  std::string path_, temp_;
  std::FILE* out_ = nullptr;
  std::uint64_t offset_ = 0;
  Checksum sum_;
};

/// A file mapped read-only. Throws Error naming the path when it cannot be opened or mapped.
class Mapping {
 public:
  explicit Mapping(const std::string& path);
  ~Mapping();
  Mapping(const Mapping&) = delete;
  Mapping& operator=(const Mapping&) = delete;
  const unsigned char* data() const { return data_; }
  std::size_t size() const { return size_; }

 private:
  const unsigned char* data_ = nullptr;
  std::size_t size_ = 0;
};

/// Reads a mapped file in one pass: the header at construction, then the chunks in order,
/// each summed into the checksum slab by slab (64 KiB) and handed to the caller's check of
/// that slab while it is in cache; finish() compares the checksum. A check that fails
/// before finish() first sums the rest of the file, so that a corrupted file is reported
/// as corrupted rather than by its first symptom. Every failure throws
/// Error("load: PATH: what was wrong").
class Reader {
 public:
  Reader(std::shared_ptr<const Mapping> map, std::string path);
  const Header& header() const { return header_; }
  /// The next chunk, which must carry `tag`, as an array of T (its size a multiple of
  /// sizeof(T)); check(std::span<const T>) sees it slab by slab, first to last.
  template <class T, class Check>
  std::span<const T> next(Tag tag, Check&& check) {
    const std::span<const unsigned char> raw = next_raw(tag, sizeof(T), [&](std::span<const unsigned char> slab) {
      check(std::span<const T>(reinterpret_cast<const T*>(slab.data()), slab.size() / sizeof(T)));
    });
    return {reinterpret_cast<const T*>(raw.data()), raw.size() / sizeof(T)};
  }
  template <class T>
  std::span<const T> next(Tag tag) {
    return next<T>(tag, [](std::span<const T>) {});
  }
  /// The next chunk as raw bytes of `item_bytes`-byte items; check(std::span<const unsigned
  /// char>) sees whole items.
  template <class Check>
  std::span<const unsigned char> next_items(Tag tag, std::size_t item_bytes, Check&& check) {
    return next_raw(tag, item_bytes, check);
  }
  /// The next chunk as exactly one T.
  template <class T>
  const T& one(Tag tag) {
    const std::span<const T> s = next<T>(tag);
    if (s.size() != 1) fail("chunk " + std::to_string(static_cast<unsigned>(tag)) + " has the wrong size");
    return s[0];
  }
  /// Checks that every chunk was read and the checksum matches.
  void finish();
  /// Throws Error("load: PATH: what"), or the checksum's error when the file is corrupted.
  [[noreturn]] void fail(const std::string& what);
  const std::shared_ptr<const Mapping>& mapping() const { return map_; }

 private:
  /// Slab callback of next_raw: a function reference without an allocation.
  struct SlabCheck {
    void* context;
    void (*call)(void* context, std::span<const unsigned char> slab);
  };
  template <class F>
  std::span<const unsigned char> next_raw(Tag tag, std::size_t item_bytes, F&& f) {
    return next_raw(tag, item_bytes,
                    SlabCheck{&f, [](void* c, std::span<const unsigned char> slab) {
                                (*static_cast<std::remove_reference_t<F>*>(c))(slab);
                              }});
  }
  std::span<const unsigned char> next_raw(Tag tag, std::size_t item_bytes, SlabCheck check);
  /// Sums the file up to byte `end` (a multiple of kStripe past the header).
  void sum_to(std::size_t end);
  std::shared_ptr<const Mapping> map_;
  std::string path_;
  Header header_{};
  std::size_t offset_ = kHeaderBytes;  ///< the next chunk
  std::size_t summed_ = kHeaderBytes;  ///< bytes summed so far
  Checksum sum_;
  bool finished_ = false;
};

}  // namespace volley::accel::file
