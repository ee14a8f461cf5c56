// Wavefront OBJ (+ MTL) loading into a SceneDesc.
#pragma once
#include <cstdint>
#include <filesystem>
#include <optional>

#include <glm/glm.hpp>

#include "io/scene_desc.h"

namespace volley::io {

/// Appends the triangles of the OBJ `file` to `into.mesh`, in file order: faces are
/// fan-triangulated (v0 v1 v2, v0 v2 v3, ...), so the triangle index is the position
/// after fan triangulation, offset by the triangles `into.mesh` already held. All of
/// the OBJ's `v` are appended to `into.mesh.positions` (unused ones too).
///
/// Geometry: `v` (x y z; a w or vertex colours after them are ignored), `vn`, `f`
/// with `v`, `v/vt`, `v//vn`, `v/vt/vn` references, positive or negative (relative)
/// indices; `vt`, `g`, `o`, `s`, `l`, `p` and unknown statements are ignored; CRLF line
/// ends and tabs are accepted. Positions are mapped by `transform` (an affine matrix),
/// normals by its inverse transpose and renormalized.
///
/// Normals: when any face corner of the file references a `vn`, the new triangles get
/// corner normals, all unit length; a corner without one, or whose transformed `vn` has
/// zero length, takes the triangle's geometric normal (for a zero-area triangle, whose
/// normals are never shaded: another corner's normal, else +z). The mesh stays consistent across calls:
/// `corner_normals` is either empty or 3 per triangle (triangles loaded earlier without
/// normals get geometric normals when a file with normals arrives, and vice versa).
///
/// Materials: with `material_override` (an index into `into.materials`) every new
/// triangle uses it and no MTL is read. Otherwise the `mtllib` files (relative to the
/// OBJ's folder) are read with tinyobjloader and each material that a `usemtl` uses is
/// appended to `into.materials` once, in order of first use (unused ones are left out
/// so that the renderer does not plan for features nobody sees); mapping: Ka→ambient,
/// Kd→diffuse, Ks→specular, Ns→shininess (tinyobjloader gives 1 when Ns is absent),
/// Ke→emission, Ni→ior, illum 3 or 5 →
/// mirror = Ks, illum 4/6/7 or d < 1 → transmittance = (1 − d, or 1 when d = 1) × (Tf,
/// or 1 when Tf is 0). Faces before any `usemtl`, or whose name no MTL defines, use the
/// "(default)" material (see mesh_append.h). A missing or unreadable MTL is not an
/// error: one warning goes to stderr and those faces use the default material.
///
/// Throws LoadError (`FILE:LINE:COL: ...`) when the file cannot be read, a number is
/// malformed, out of float range or not finite, an index is 0 or refers to a vertex /
/// normal that does not exist, or a face has fewer than 3 vertices. A file without
/// faces is not an error. On any exception `into` is left unchanged.
/// Throws std::invalid_argument when `material_override` is not an index into
/// `into.materials`.
void load_obj(const std::filesystem::path& file, const glm::mat4& transform,
              std::optional<std::uint32_t> material_override, SceneDesc& into);

}  // namespace volley::io
