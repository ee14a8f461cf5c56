// The materials of an OBJ file's triangles: the MTL libraries its mtllib lines name, read
// with tinyobjloader's MTL reader and mapped to Phong materials (obj_loader.h documents the
// mapping), and the usemtl name of each triangle resolved against them.
#pragma once
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "io/scene_desc.h"

namespace volley::io {

/// A triangle before any usemtl, or a usemtl name no library defines.
inline constexpr std::uint32_t kNoMaterialSlot = 0xffffffffu;

/// An mtllib line: the library's file name as written (relative to the OBJ file) and its line.
struct MtlLibrary {
  std::string name;
  std::size_t line;
};

/// What the OBJ parser records of materials.
struct ObjMaterialUse {
  const std::vector<MtlLibrary>& libraries;       ///< in the order of the mtllib lines
  const std::vector<std::string>& slot_names;     ///< usemtl names in order of first use
  const std::vector<std::uint32_t>& triangle_slot;  ///< per triangle: index into slot_names or kNoMaterialSlot
};

/// Material index of every triangle: the override, or the MTL material its usemtl names
/// (appended to `materials` on first use; the first library to define a name wins), or the
/// default material (ensure_default_material). A library that is missing or not a regular
/// file, and names no library defines, are warnings on stderr naming the file and line.
std::vector<std::uint32_t> obj_triangle_materials(const std::filesystem::path& file, const ObjMaterialUse& use,
                                                  std::optional<std::uint32_t> material_override,
                                                  std::vector<Material>& materials);

}  // namespace volley::io
