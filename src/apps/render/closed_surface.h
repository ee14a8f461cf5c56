// Whether a scene's faces bound closed solids: every edge, taken with its direction
// around each face, is met exactly once in each direction (two faces share it, with
// opposite orientation). Then a segment between two points outside every solid that
// crosses a solid enters it through a front face, so occlusion rays from outside may
// ignore back faces when all materials are opaque (back-face culling is admissible).
// Vertices are matched by exact position, so meshes split at texture or normal seams
// (separate indices for the same point) still count as closed.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

namespace volley::core {

/// What the check found.
struct ClosureReport {
  std::size_t edges = 0;      ///< directed edges of non-degenerate length
  std::size_t unmatched = 0;  ///< edges without exactly one opposite partner (open, non-manifold, flipped)
  /// Closed and consistently oriented (a scene without faces is not).
  bool closed() const { return edges > 0 && unmatched == 0; }
};

/// Collects the faces of a scene (triangles and polygons alike), then checks them once.
class ClosureCheck {
 public:
  /// Adds a face given by its corners in boundary order (n >= 2; a zero-length edge, as in
  /// a triangle with a repeated corner, is ignored).
  void add_face(const glm::vec3* corners, std::size_t n);
  /// The triangles of an indexed mesh (3 indices each).
  void add_triangles(const std::vector<glm::vec3>& positions, const std::vector<std::uint32_t>& indices);
  /// Matches the edges: vertices are welded by exact position, then every undirected edge
  /// must be met twice, once in each direction. O(E log E) for E edges; at most 2^31 corners.
  ClosureReport finish();

 private:
  std::vector<glm::vec3> points_;                    // every corner added
  std::vector<std::array<std::uint32_t, 2>> edges_;  // directed, as indices into points_
};

}  // namespace volley::core
