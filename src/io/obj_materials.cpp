#include "io/obj_materials.h"

#include <tiny_obj_loader.h>

#include <algorithm>
#include <fstream>
#include <iostream>
#include <map>
#include <system_error>
#include <utility>

#include "io/mesh_append.h"

namespace volley::io {
namespace {

std::string trimmed(std::string s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return {};
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

glm::vec3 vec3_of(const tinyobj::real_t (&a)[3]) { return {a[0], a[1], a[2]}; }

/// MTL → Phong material with the notes' global terms (mapping documented in obj_loader.h).
Material material_from_mtl(const tinyobj::material_t& m) {
  Material out;
  out.name = trimmed(m.name);
  out.ambient = vec3_of(m.ambient);
  out.diffuse = vec3_of(m.diffuse);
  out.specular = vec3_of(m.specular);
  out.shininess = m.shininess;
  out.emission = vec3_of(m.emission);
  out.ior = m.ior;
  if (m.illum == 3 || m.illum == 5) out.mirror = out.specular;
  const bool refracting = m.illum == 4 || m.illum == 6 || m.illum == 7;
  if (refracting || m.dissolve < 1.0f) {
    const float amount = m.dissolve < 1.0f ? 1.0f - std::max(m.dissolve, 0.0f) : 1.0f;
    glm::vec3 filter = vec3_of(m.transmittance);
    if (filter == glm::vec3(0.0f)) filter = glm::vec3(1.0f);
    out.transmittance = amount * filter;
  }
  return out;
}

void warn(const std::string& message) { std::cerr << "warning: " << message << '\n'; }

/// The materials of every mtllib the file names, first definition of a name winning.
std::map<std::string, Material> read_libraries(const std::filesystem::path& file,
                                               const std::vector<MtlLibrary>& libraries) {
  std::map<std::string, Material> by_name;
  for (const auto& lib : libraries) {
    const std::filesystem::path path = file.parent_path() / lib.name;
    const std::string where = file.string() + ':' + std::to_string(lib.line) + ": ";
    std::error_code ec;
    if (std::filesystem::exists(path, ec) && !std::filesystem::is_regular_file(path, ec)) {
      // A device or pipe (mtllib /dev/zero) could be endless.
      warn(where + "material library \"" + lib.name + "\" is not a regular file (" + path.string() +
           "); its materials use the default material");
      continue;
    }
    std::ifstream in(path, std::ios::binary);
    if (!in) {
      warn(where + "material library \"" + lib.name + "\" not found (looked for " + path.string() +
           "); its materials use the default material");
      continue;
    }
    std::map<std::string, int> index_of_name;
    std::vector<tinyobj::material_t> materials;
    std::string warnings, errors;
    tinyobj::LoadMtl(&index_of_name, &materials, &in, &warnings, &errors);
    if (!warnings.empty() || !errors.empty()) warn(where + path.string() + ": " + trimmed(warnings + errors));
    for (const auto& m : materials) {
      Material converted = material_from_mtl(m);
      by_name.try_emplace(converted.name, std::move(converted));
    }
  }
  return by_name;
}

}  // namespace

std::vector<std::uint32_t> obj_triangle_materials(const std::filesystem::path& file, const ObjMaterialUse& obj,
                                                  std::optional<std::uint32_t> material_override,
                                                  std::vector<Material>& materials) {
  const std::size_t triangles = obj.triangle_slot.size();
  if (material_override) return std::vector<std::uint32_t>(triangles, *material_override);

  const std::map<std::string, Material> library = read_libraries(file, obj.libraries);
  std::vector<std::uint32_t> material_of_slot(obj.slot_names.size(), kNoMaterialSlot);
  std::vector<std::string> undefined;
  for (std::size_t s = 0; s < obj.slot_names.size(); ++s) {
    const auto it = library.find(obj.slot_names[s]);
    if (it == library.end()) {
      undefined.push_back(obj.slot_names[s]);
      continue;
    }
    material_of_slot[s] = static_cast<std::uint32_t>(materials.size());
    materials.push_back(it->second);
  }
  if (!undefined.empty())
    warn(file.string() + ": " + std::to_string(undefined.size()) +
         " material name(s) used by usemtl but defined in no material library (\"" + undefined.front() + "\"" +
         (undefined.size() > 1 ? ", ..." : "") + "); their faces use the default material");

  std::vector<std::uint32_t> result(triangles);
  std::uint32_t fallback = kNoMaterialSlot;
  for (std::size_t t = 0; t < triangles; ++t) {
    const std::uint32_t slot = obj.triangle_slot[t];
    std::uint32_t m = slot == kNoMaterialSlot ? kNoMaterialSlot : material_of_slot[slot];
    if (m == kNoMaterialSlot) {
      if (fallback == kNoMaterialSlot) fallback = ensure_default_material(materials);
      m = fallback;
    }
    result[t] = m;
  }
  return result;
}

}  // namespace volley::io
