// A scene as plain data, exactly as read from a .json scene or a bare mesh: no
// acceleration structure, no derived quantities. Loaders fill it; the renderer reads it.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace volley::io {

/// Camera in either form the scene file allows. The renderer builds the notes' camera
/// (eye, u v w basis, focal distance f, window wl wr wt wb) from it.
struct CameraDesc {
  enum class Kind { notes, look_at };
  Kind kind = Kind::look_at;
  glm::vec3 eye{0, 0, 0};
  // look_at form
  glm::vec3 target{0, 0, -1};
  glm::vec3 up{0, 1, 0};
  float fov_deg = 45.0f;  ///< vertical field of view
  // notes form: image plane at eye + f w, window in camera coordinates
  glm::vec3 u{1, 0, 0}, v{0, 1, 0}, w{0, 0, -1};
  float f = 1.0f;
  float wl = -1, wr = 1, wt = 1, wb = -1;
};

/// Phong material with the notes' global terms. Colours are linear RGB in [0, 1]
/// (emission may exceed 1).
struct Material {
  std::string name;
  glm::vec3 ambient{0.1f};
  glm::vec3 diffuse{0.7f};
  glm::vec3 specular{0.0f};
  float shininess = 32.0f;
  glm::vec3 mirror{0.0f};         ///< mirror reflectance
  glm::vec3 transmittance{0.0f};  ///< refracted fraction (glass: near 1)
  float ior = 1.0f;               ///< index of refraction inside the surface
  glm::vec3 emission{0.0f};
};

/// Point light; intensity is radiant intensity per colour channel (falls off as 1/d^2).
struct PointLight {
  glm::vec3 position{0.0f};
  glm::vec3 intensity{1.0f};
};

/// A scene object made of triangles: its run of the merged mesh's triangles.
struct ObjectDesc {
  std::string name;                ///< the object's "name", else its JSON path or file name
  std::size_t first_triangle = 0;  ///< index of its first triangle in MeshDesc
  std::size_t triangle_count = 0;
  std::uint32_t mask = 0xffffffffu;  ///< the object's "mask" (Accel::set_geometry_mask)
};

/// All triangles of the scene merged in one indexed mesh (object transforms applied),
/// in file order, and the objects they came from (one geometry each in the Accel).
struct MeshDesc {
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices;        ///< 3 per triangle
  std::vector<std::uint32_t> material;       ///< 1 per triangle, index into SceneDesc::materials
  std::vector<glm::vec3> corner_normals;     ///< 3 per triangle, or empty (use geometric normals)
  std::vector<ObjectDesc> objects;           ///< in order, covering every triangle once
  std::size_t triangle_count() const { return indices.size() / 3; }
};

/// A planar polygon (convex or concave) given by its boundary in order.
struct PolygonDesc {
  std::string name;
  std::vector<glm::vec3> vertices;
  std::uint32_t material = 0;
  std::uint32_t mask = 0xffffffffu;  ///< the object's "mask" (Accel::set_geometry_mask)
};

/// Render settings a scene may carry; command-line options override them.
struct RenderSettings {
  int width = 512;
  int height = 512;
  int spp = 1;
  int max_depth = 5;
  std::string integrator = "whitted";  ///< "whitted" or "path"
  glm::vec3 background{0.0f};
  std::uint64_t seed = 1;
};

/// An "instance" object: a triangle object placed again under a transform (the renderer
/// builds the object alone as a prototype and adds it to the scene with Accel::add_instance).
struct InstanceDesc {
  std::string name;
  std::size_t object = 0;           ///< index in MeshDesc::objects of the object it places ("of")
  glm::mat4 transform{1.0f};
  std::uint32_t mask = 0xffffffffu;
  /// The transform as Accel::add_instance takes it: the 3x4 matrix [A | t] row by row.
  std::array<float, 12> rows() const {
    const glm::mat4& m = transform;  // column-major: m[column][row]
    return {m[0][0], m[1][0], m[2][0], m[3][0], m[0][1], m[1][1], m[2][1], m[3][1], m[0][2], m[1][2], m[2][2], m[3][2]};
  }
};

struct SceneDesc {
  std::string source;      ///< file it came from (for messages)
  bool has_camera = false; ///< false: the renderer frames the bounds automatically
  CameraDesc camera;
  RenderSettings settings;
  std::vector<Material> materials;  ///< never empty after loading (a default is added)
  std::vector<PointLight> lights;
  MeshDesc mesh;
  std::vector<PolygonDesc> polygons;
  std::vector<InstanceDesc> instances;
};

}  // namespace volley::io
