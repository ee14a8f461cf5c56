#include "io/mesh_append.h"

#include <cmath>
#include <string>

#include "io/load_error.h"

namespace volley::io {

Material default_material() {
  Material m;
  m.name = std::string(kDefaultMaterialName);
  m.ambient = glm::vec3(0.1f);
  m.diffuse = glm::vec3(0.7f);
  m.specular = glm::vec3(0.1f);
  m.shininess = 32.0f;
  return m;
}

void transform_positions(const std::filesystem::path& file, const glm::mat4& transform,
                         std::vector<glm::vec3>& positions, std::size_t first_number) {
  if (transform == glm::mat4(1.0f)) return;
  for (std::size_t i = 0; i < positions.size(); ++i) {
    positions[i] = glm::vec3(transform * glm::vec4(positions[i], 1.0f));
    if (!std::isfinite(positions[i].x) || !std::isfinite(positions[i].y) || !std::isfinite(positions[i].z))
      throw LoadError(file, "vertex " + std::to_string(i + first_number) + " is not finite after the object transform");
  }
}

std::uint32_t ensure_default_material(std::vector<Material>& materials) {
  for (std::size_t i = 0; i < materials.size(); ++i)
    if (materials[i].name == kDefaultMaterialName) return static_cast<std::uint32_t>(i);
  materials.push_back(default_material());
  return static_cast<std::uint32_t>(materials.size() - 1);
}

glm::vec3 geometric_normal(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
  // In double: the cross product of a tiny (but valid) triangle underflows in float.
  const glm::dvec3 n = glm::cross(glm::dvec3(b) - glm::dvec3(a), glm::dvec3(c) - glm::dvec3(a));
  const double len = glm::length(n);
  // len > 0 is false for NaN as well; positions are checked finite before this is called.
  return len > 0.0 ? glm::vec3(n / len) : glm::vec3(0.0f);
}

void complete_corner_normals(MeshDesc& mesh) {
  const std::size_t count = mesh.triangle_count();
  mesh.corner_normals.reserve(3 * count);
  for (std::size_t t = mesh.corner_normals.size() / 3; t < count; ++t) {
    glm::vec3 n = geometric_normal(mesh.positions[mesh.indices[3 * t]], mesh.positions[mesh.indices[3 * t + 1]],
                                   mesh.positions[mesh.indices[3 * t + 2]]);
    if (n == glm::vec3(0.0f)) n = glm::vec3(0, 0, 1);  // zero-area triangle: never hit, any unit vector will do
    mesh.corner_normals.insert(mesh.corner_normals.end(), 3, n);
  }
}

}  // namespace volley::io
