// ASCII PLY loading into a SceneDesc.
#pragma once
#include <cstdint>
#include <filesystem>
#include <optional>

#include <glm/glm.hpp>

#include "io/scene_desc.h"

namespace volley::io {

/// Appends the triangles of the ASCII PLY `file` to `into.mesh`, with the semantics of
/// load_obj: faces fan-triangulated in file order, positions mapped by `transform`,
/// every new triangle using `material_override` or else the "(default)" material, and
/// corner_normals kept empty or 3 per triangle (PLY triangles get geometric normals
/// when the mesh already carries corner normals).
///
/// Reads `format ascii 1.0`; the `vertex` element needs properties x, y, z (any other
/// properties, e.g. confidence or intensity, are skipped); the `face` element needs a
/// list property `vertex_indices` (or `vertex_index`); other elements and properties are
/// skipped. Throws LoadError (`FILE:LINE:COL: ...`) for a binary PLY ("binary PLY not
/// supported"), a malformed header, a malformed or non-finite number, an index outside
/// the vertex list, a face with fewer than 3 vertices, or a file that ends early.
/// On any exception `into` is left unchanged. Throws std::invalid_argument when
/// `material_override` is not an index into `into.materials`.
void load_ply(const std::filesystem::path& file, const glm::mat4& transform,
              std::optional<std::uint32_t> material_override, SceneDesc& into);

}  // namespace volley::io
