// The renderer's view of a scene: the committed Accel plus what shading needs (materials,
// lights, per-primitive normals) and the camera. Built once from a SceneDesc.
#pragma once
#include <cstdint>
#include <glm/glm.hpp>
#include <string>
#include <vector>

#include "render/camera.h"
#include "io/scene_desc.h"
#include "volley/accel.h"

namespace volley::render {

/// What the scene contains, so the renderer can skip the rest (--stats prints it).
struct SceneFeatures {
  bool lights = false;      ///< point lights present: shadow rays needed
  bool mirrors = false;     ///< a material with mirror reflectance
  bool refraction = false;  ///< a material with transmittance
  bool emission = false;    ///< an emissive material
  bool polygons = false;
  bool smooth_normals = false;  ///< per-corner normals to interpolate
  /// Every triangle and polygon bounds a closed, consistently oriented solid
  /// (render/closed_surface.h); open_edges counts the edges that keep it from being so.
  /// Filled by with_closure() only (Scene::features() leaves them false and 0).
  bool closed = false;
  std::size_t open_edges = 0;
  /// Back-face culling is admissible for occlusion rays: all geometry closed and every
  /// material opaque (no transmittance), so a shadow ray between two points outside the
  /// solids that is blocked at all is blocked by a front face.
  bool cull_admissible() const { return closed && !refraction; }
};

/// A surface point ready for shading.
struct SurfacePoint {
  glm::vec3 p;        ///< hit point, from barycentrics (triangles) or the plane (polygons)
  glm::vec3 p_error;  ///< absolute error bound of p per axis
  glm::vec3 ng;       ///< unit geometric normal, facing the incoming ray
  glm::vec3 ns;       ///< unit shading normal, same hemisphere as ng
  bool front = true;  ///< the ray hit the side the geometric normal points to (outside)
  std::uint32_t material = 0;
};

class Scene {
 public:
  /// Builds from a loaded description. `width`/`height` size the camera; a description
  /// without a camera (a bare mesh) gets one framing its bounds, and one without lights a
  /// light above the camera. Throws volley::Error for invalid geometry (naming the polygon).
  /// With `structure` (a file Accel::save wrote for this scene: `volley trace --save`) the
  /// Accel is loaded from it instead of built (its options are the file's); Error when the
  /// file's geometries do not match the scene's.
  Scene(const io::SceneDesc& desc, int width, int height, const Options& options, const std::string& structure = {});

  const Accel& accel() const { return accel_; }
  /// A hit's primitive in the merged numbering of positions() / indices() (triangles
  /// first, then polygons): the Accel reports the geometry and the index within it.
  /// A hit through an instance is numbered as the triangle of the object it places.
  std::uint32_t prim_index(const Hit& hit) const {
    return geometry_base_[hit.inst != kInvalidId ? hit.inst : hit.geom] + hit.prim;
  }
  /// The world-space vertices of a triangle hit (moved by its instance's transform, if any).
  void triangle_vertices(const Hit& hit, glm::vec3& p0, glm::vec3& p1, glm::vec3& p2) const {
    const std::uint32_t* idx = &indices_[3 * std::size_t(prim_index(hit))];
    p0 = positions_[idx[0]], p1 = positions_[idx[1]], p2 = positions_[idx[2]];
    if (hit.inst == kInvalidId) return;
    const glm::mat4& m = instances_[instance_slot_[hit.inst]].to_world;
    p0 = glm::vec3(m * glm::vec4(p0, 1.0f)), p1 = glm::vec3(m * glm::vec4(p1, 1.0f)),
    p2 = glm::vec3(m * glm::vec4(p2, 1.0f));
  }
  const core::Camera& camera() const { return camera_; }
  const std::vector<io::Material>& materials() const { return materials_; }
  const std::vector<io::PointLight>& lights() const { return lights_; }
  const SceneFeatures& features() const { return features_; }
  const glm::vec3& background() const { return background_; }
  /// Scene bounds diagonal (sets the scale for automatic camera and light).
  float extent() const { return extent_; }

  /// Shading data for a hit of `ray` (a hit, not a miss).
  SurfacePoint surface(const Ray& ray, const Hit& hit) const { return surface_as<true>(ray, hit); }
  /// The same; with Smooth = false the shading normal is the geometric one (no
  /// interpolation of per-corner normals, for scenes that have none).
  template <bool Smooth>
  SurfacePoint surface_as(const Ray& ray, const Hit& hit) const;

  /// Triangles (prim ids 0 .. triangle_count() - 1): vertex positions, 3 indices and a
  /// material per triangle. Polygons follow them in prim-id order.
  std::size_t triangle_count() const { return tri_material_.size(); }
  const std::vector<glm::vec3>& positions() const { return positions_; }
  const std::vector<std::uint32_t>& indices() const { return indices_; }
  const std::vector<std::uint32_t>& triangle_materials() const { return tri_material_; }

 private:
  Accel accel_;
  std::vector<std::uint32_t> geometry_base_;  ///< per geometry id: its first primitive's merged index
  core::Camera camera_;
  std::vector<io::Material> materials_;
  std::vector<io::PointLight> lights_;
  SceneFeatures features_;
  glm::vec3 background_{0.0f};
  float extent_ = 1.0f;
  // Triangles: prim ids 0 .. T-1 in mesh order; polygons follow.
  std::vector<glm::vec3> positions_;
  std::vector<std::uint32_t> indices_;
  std::vector<std::uint32_t> tri_material_;
  std::vector<glm::vec3> corner_normals_;
  struct PolygonShading {
    glm::vec3 normal;
    float d;
    std::uint32_t material;
  };
  std::vector<PolygonShading> polygons_;
  /// The scene's "instance" objects: the prototypes (one Accel per object placed) and,
  /// per instance, its transform; instance_slot_ maps a geometry id to its entry.
  struct InstanceShading {
    glm::mat4 to_world;
    glm::mat3 normal;   ///< inverse transpose of the 3x3 part
    float translation;  ///< largest |translation| (for the hit point's error bound)
  };
  std::vector<Accel> prototypes_;
  std::vector<InstanceShading> instances_;
  std::vector<std::uint32_t> instance_slot_;
  // The constructor's steps: the geometries added to accel_ (or only counted when `load`,
  // the structure coming from a saved file), the saved structure checked against them, the
  // features the pipeline reads.
  void add_objects(const io::SceneDesc& desc, bool load);
  void add_polygons(const io::SceneDesc& desc, bool load);
  void add_instances(const io::SceneDesc& desc, const Options& options);
  void load_structure(const std::string& structure);
  void note_features();
};

/// scene.features() with the closed-and-opaque analysis filled in (closed, open_edges) from
/// the scene's triangles and desc's polygons (the desc the scene was made from). Not part of
/// the constructor: it costs about a third of a BVH build, no pipeline uses it yet (culling is
/// not wired), and only `volley info` and `render --stats` report it.
SceneFeatures with_closure(const Scene& scene, const io::SceneDesc& desc);

}  // namespace volley::render
