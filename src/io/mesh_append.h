// Helpers the loaders share to append to a SceneDesc while keeping its invariants:
// corner_normals is empty or holds 3 normals per triangle; a default material exists
// for geometry that names none.
#pragma once
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "io/scene_desc.h"

namespace volley::io {

/// Name of the material loaders add for geometry without one ("(default)": the
/// parentheses keep it apart from names a scene or MTL file can define).
inline constexpr std::string_view kDefaultMaterialName = "(default)";

/// Light grey Phong material: ambient 0.1, diffuse 0.7, specular 0.1, shininess 32.
Material default_material();

/// Index of the material named kDefaultMaterialName in `materials`, appending
/// default_material() first when there is none.
std::uint32_t ensure_default_material(std::vector<Material>& materials);

/// Unit normal of the triangle (a, b, c) by the right-hand rule; (0, 0, 0) when the
/// triangle has zero area (such a triangle is never hit, so the value is never shaded).
glm::vec3 geometric_normal(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c);

/// Moves a loaded file's vertices by the object transform, each checked finite (the
/// identity is skipped, so that coordinates stay bit-exact). Throws LoadError naming `file`
/// and the first vertex that is not finite afterwards, numbered as the file numbers its
/// vertices (from `first_number`: OBJ 1, PLY 0).
void transform_positions(const std::filesystem::path& file, const glm::mat4& transform,
                         std::vector<glm::vec3>& positions, std::size_t first_number);

/// Gives every triangle past the last one with corner normals its geometric normal
/// at all three corners ((0, 0, 1) for a zero-area triangle), so that
/// corner_normals.size() == 3 * triangle_count() afterwards and every normal is unit length.
void complete_corner_normals(MeshDesc& mesh);

}  // namespace volley::io
