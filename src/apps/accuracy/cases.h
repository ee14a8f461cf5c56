// The ray sets of the accuracy report: closed meshes with vertex/edge/diagonal-aimed rays
// from inside, random triangles with random aimed rays (both moved by the report's
// offsets), and the shared meshes with primary and random rays.
#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include "accuracy/mesh.h"

namespace volley::accuracy {

/// One mesh and the rays traced through it.
struct Case {
  std::string set;      ///< "closed", "random" or "scene"
  std::string name;     ///< "cube8", "icosphere3", "triangles500", "bunny/primary", ...
  double offset = 0;    ///< every coordinate moved by this (closed and random sets)
  bool closed = false;  ///< rays start inside a closed mesh: a miss is a leak
  Mesh mesh;
  std::vector<Ray> rays;
  std::size_t exact_targets = 0, targets = 0;  ///< closed: targets still exact after the offset
};

/// Offsets of the closed and random sets.
inline constexpr float kOffsets[] = {0.0f, 1e3f, 1e5f, 1e6f};

/// Closed grid cube (n = 8) and icosphere (3 levels, radius 1000) at every offset; about
/// 20 thousand rays each times `repeat` (more interior origins).
std::vector<Case> closed_cases(std::size_t repeat = 1);
/// How many closed_cases() there are, and the k-th alone (the long run makes them one by one).
std::size_t closed_case_count();
Case closed_case(std::size_t k, std::size_t repeat);
/// 500 random triangles in a unit box at every offset, `rays` random rays from a 3-unit
/// box aimed at interior points of random triangles.
std::vector<Case> random_triangle_cases(std::size_t rays);

/// The shared meshes the report uses when present in `scenes_dir`.
inline const char* const kSceneMeshes[] = {"stanford-bunny.obj", "dragon_100k.obj"};
/// For each of kSceneMeshes found: "<mesh>/primary" (one camera ray per pixel of a
/// `size` x `size` image, automatic camera, 4x4 blocks) and "<mesh>/random" (size^2 rays
/// from its bounding box, enlarged, aimed at random interior points of random triangles).
/// `missing` receives the files not found. At most `max_meshes` meshes are loaded.
std::vector<Case> scene_cases(const std::filesystem::path& scenes_dir, int size, std::vector<std::string>& missing,
                              std::size_t max_meshes = std::size(kSceneMeshes));

}  // namespace volley::accuracy
