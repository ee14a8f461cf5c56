// volley public API: the acceleration structure an embedder builds and queries.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>

#include "volley/options.h"
#include "volley/ray.h"

namespace volley {

/// Thrown for invalid input to the API (bad indices, NaN vertices, non-planar polygon,
/// query before commit). The message says what was expected.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Facts about a committed Accel (for `volley info` and --stats).
struct AccelInfo {
  std::size_t triangles = 0;       ///< triangles added
  std::size_t degenerate = 0;      ///< zero-area triangles among them (never hit)
  std::size_t polygons = 0;        ///< planar polygons added
  std::size_t nodes = 0;           ///< BVH nodes
  std::size_t leaves = 0;          ///< BVH leaves
  std::size_t depth = 0;           ///< deepest leaf
  double sah_cost = 0.0;           ///< SAH cost (traversal step = 1, triangle test = 1)
  double mean_leaf_size = 0.0;     ///< primitives per leaf
  std::size_t bytes = 0;           ///< memory of nodes + primitive data
  double build_seconds = 0.0;      ///< wall time of commit
  TriangleTest test = TriangleTest::watertight;
  Isa isa = Isa::scalar;           ///< ISA actually used
};

/// Triangles and planar polygons, built once by commit(), then queried.
/// Not thread-safe while adding/committing; after commit() it is immutable and any number
/// of threads may call intersect()/occluded() concurrently.
class Accel {
 public:
  Accel();
  ~Accel();
  Accel(Accel&&) noexcept;
  Accel& operator=(Accel&&) noexcept;
  Accel(const Accel&) = delete;
  Accel& operator=(const Accel&) = delete;

  /// Adds an indexed triangle mesh. `xyz` holds 3*vertex_count floats, `indices`
  /// 3*triangle_count vertex indices. Data is copied. Prim ids are assigned in order,
  /// continuing from earlier additions; returns the id of the first triangle.
  /// Throws Error for an index out of range or a non-finite vertex.
  std::uint32_t add_triangles(const float* xyz, std::size_t vertex_count,
                              const std::uint32_t* indices, std::size_t triangle_count);

  /// Adds one planar polygon (convex or concave, >= 3 vertices, 3*vertex_count floats,
  /// in order around the boundary). Returns its prim id. Throws Error when it is not
  /// planar within 1e-4 of its size, has a non-finite vertex or zero area.
  std::uint32_t add_polygon(const float* xyz, std::size_t vertex_count);

  /// Builds the acceleration structure. Call again after adding more geometry.
  void commit(const Options& options = {});

  /// Closest hit along the ray (tmin <= t < tmax), or a miss.
  Hit intersect(const Ray& ray) const;
  /// True when anything is hit with tmin <= t < tmax.
  bool occluded(const Ray& ray) const;

  /// Facts about the committed structure.
  AccelInfo info() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace volley
