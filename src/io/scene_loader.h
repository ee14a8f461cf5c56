// Scene loading: a JSON scene file, or a bare mesh (.obj / .ply).
#pragma once
#include <filesystem>

#include "io/scene_desc.h"

namespace volley::io {

/// Loads the scene `file` by its extension (case-insensitive):
/// - `.json`: a scene file (format: docs_scene_format.md / README "Scene files").
///   Mesh paths are relative to the scene file's folder; a path starting with
///   `${scenes}/` is looked up in `shared_scenes_dir` (the caller's --scenes /
///   VOLLEY_SCENES / ../shared/scenes; may be empty when no scene uses it).
/// - `.obj` / `.ply`: a bare mesh: has_camera = false, no lights, default settings,
///   the OBJ's MTL materials or else one "(default)" material (light grey diffuse 0.7,
///   specular 0.1); see is_bare_mesh().
/// The result has source = file, at least one material, and at least one triangle or
/// polygon. Throws LoadError for anything wrong with the file or the files it names
/// (messages `FILE:LINE:COL: ...` or `FILE: JSON.PATH: ...`), including a scene
/// without geometry ("scene has no geometry"). Warnings (a missing MTL file, undefined
/// usemtl names) go to std::cerr. Safe to call from several threads at once.
SceneDesc load_scene(const std::filesystem::path& file, const std::filesystem::path& shared_scenes_dir);

/// True for a scene without a camera and without lights (a bare mesh, or a JSON scene
/// that gives neither): the renderer then frames the bounds and adds a light.
inline bool is_bare_mesh(const SceneDesc& scene) { return !scene.has_camera && scene.lights.empty(); }

}  // namespace volley::io
