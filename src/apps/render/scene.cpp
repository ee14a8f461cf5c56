#include "render/scene.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "render/closed_surface.h"
#include "render/spawn.h"

namespace volley::render {
namespace {

struct Bounds {
  glm::vec3 lo{std::numeric_limits<float>::infinity()};
  glm::vec3 hi{-std::numeric_limits<float>::infinity()};
  void extend(const glm::vec3& p) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
};

Bounds object_bounds(const io::MeshDesc& mesh, const io::ObjectDesc& o) {
  Bounds b;
  for (std::size_t k = 3 * o.first_triangle; k < 3 * (o.first_triangle + o.triangle_count); ++k)
    b.extend(mesh.positions[mesh.indices[k]]);
  return b;
}

Bounds scene_bounds(const io::SceneDesc& desc) {
  Bounds b;
  for (const auto& p : desc.mesh.positions) b.extend(p);
  for (const auto& poly : desc.polygons)
    for (const auto& p : poly.vertices) b.extend(p);
  std::vector<Bounds> objects(desc.mesh.objects.size());
  std::vector<bool> known(desc.mesh.objects.size(), false);
  for (const io::InstanceDesc& in : desc.instances) {
    if (!known[in.object])
      objects[in.object] = object_bounds(desc.mesh, desc.mesh.objects[in.object]), known[in.object] = true;
    const Bounds& o = objects[in.object];
    if (!(o.lo.x <= o.hi.x)) continue;
    for (int c = 0; c < 8; ++c)
      b.extend(glm::vec3(in.transform *
                         glm::vec4(c & 1 ? o.hi.x : o.lo.x, c & 2 ? o.hi.y : o.lo.y, c & 4 ? o.hi.z : o.lo.z, 1.0f)));
  }
  return b;
}

// The notes' camera from the description, or one framing the bounds from the front
// (+z side, slightly above) for a bare mesh.
core::Camera make_camera(const io::SceneDesc& desc, const Bounds& b, int width, int height) {
  const io::CameraDesc& c = desc.camera;
  if (desc.has_camera && c.kind == io::CameraDesc::Kind::notes)
    return core::Camera(c.eye, c.u, c.v, c.w, c.f, c.wl, c.wr, c.wt, c.wb, width, height);
  if (desc.has_camera) return core::Camera::look_at(c.eye, c.target, c.up, c.fov_deg, width, height);
  const glm::vec3 center = 0.5f * (b.lo + b.hi);
  const float radius = std::max(0.5f * glm::length(b.hi - b.lo), 1e-6f);
  const float fov = 40.0f;
  const float distance = radius / std::sin(glm::radians(fov) * 0.5f) * 1.05f;
  const glm::vec3 dir = glm::normalize(glm::vec3(0.35f, 0.3f, 1.0f));
  return core::Camera::look_at(center + dir * distance, center, {0, 1, 0}, fov, width, height);
}

}  // namespace

Scene::Scene(const io::SceneDesc& desc, int width, int height, const Options& options, const std::string& structure)
    : camera_(make_camera(desc, scene_bounds(desc), width, height)),
      materials_(desc.materials),
      lights_(desc.lights),
      background_(desc.settings.background),
      positions_(desc.mesh.positions),
      indices_(desc.mesh.indices),
      tri_material_(desc.mesh.material),
      corner_normals_(desc.mesh.corner_normals) {
  if (materials_.empty()) materials_.push_back(io::Material{"default"});
  const Bounds b = scene_bounds(desc);
  extent_ = std::max(glm::length(b.hi - b.lo), 1e-6f);
  if (lights_.empty() && !desc.has_camera) {
    // A bare mesh: one light over the camera's shoulder giving half the irradiance of a
    // unit light at unit distance at the mesh centre (mid-grey on a 0.7 albedo surface).
    const glm::vec3 center = 0.5f * (b.lo + b.hi);
    const glm::vec3 pos = camera_.eye() + glm::vec3(0.0f, 0.5f * extent_, 0.0f);
    const float d = glm::length(pos - center);
    lights_.push_back({pos, glm::vec3(0.5f * d * d)});
  }

  // One geometry per object (a whole mesh made by hand, without objects, is one), then one
  // per polygon; prim_index() turns a hit back into the merged mesh's numbering.
  const bool load = !structure.empty();
  add_objects(desc, load);
  add_polygons(desc, load);
  add_instances(desc, options);
  if (load)
    load_structure(structure);
  else
    accel_.commit(options);
  note_features();
}

void Scene::add_objects(const io::SceneDesc& desc, bool load) {
  std::vector<io::ObjectDesc> objects = desc.mesh.objects;
  if (objects.empty() && !indices_.empty()) objects.push_back({"mesh", 0, indices_.size() / 3});
  for (const io::ObjectDesc& o : objects) {
    if (positions_.empty()) break;
    if (!load) {
      const std::uint32_t id = accel_.add_triangles(&positions_[0].x, positions_.size(),
                                                    indices_.data() + 3 * o.first_triangle, o.triangle_count);
      if (o.mask != kMaskAll) accel_.set_geometry_mask(id, o.mask);
    }
    geometry_base_.push_back(static_cast<std::uint32_t>(o.first_triangle));
  }
}

void Scene::add_polygons(const io::SceneDesc& desc, bool load) {
  for (const auto& poly : desc.polygons) {
    geometry_base_.push_back(static_cast<std::uint32_t>(indices_.size() / 3 + polygons_.size()));
    try {
      if (!load) {
        const std::uint32_t id =
            accel_.add_polygon(reinterpret_cast<const float*>(poly.vertices.data()), poly.vertices.size());
        if (poly.mask != kMaskAll) accel_.set_geometry_mask(id, poly.mask);
      }
    } catch (const Error& e) {
      throw Error("polygon '" + poly.name + "': " + e.what());
    }
    // Newell's normal of the boundary; add_polygon has checked planarity and area.
    glm::dvec3 n(0.0);
    const auto& v = poly.vertices;
    for (std::size_t i = 0; i < v.size(); ++i) {
      const glm::dvec3 a(v[i]), c(v[(i + 1) % v.size()]);
      n += glm::dvec3((a.y - c.y) * (a.z + c.z), (a.z - c.z) * (a.x + c.x), (a.x - c.x) * (a.y + c.y));
    }
    const glm::vec3 unit(glm::normalize(n));
    glm::dvec3 centroid(0.0);
    for (const auto& p : v) centroid += glm::dvec3(p);
    centroid /= double(v.size());
    polygons_.push_back({unit, float(glm::dot(glm::dvec3(unit), centroid)), poly.material});
  }
}

void Scene::load_structure(const std::string& structure) {
  accel_ = Accel::load(structure);
  const AccelInfo info = accel_.info();
  if (info.geometries != geometry_base_.size() || info.triangles != indices_.size() / 3 ||
      info.polygons != polygons_.size())
    throw Error(structure + " holds " + std::to_string(info.geometries) + " geometries (" +
                std::to_string(info.triangles) + " triangles, " + std::to_string(info.polygons) +
                " polygons), the scene " + std::to_string(geometry_base_.size()) + " (" +
                std::to_string(indices_.size() / 3) + ", " + std::to_string(polygons_.size()) +
                "): it was saved from another scene");
}

void Scene::note_features() {
  features_.lights = !lights_.empty();
  features_.polygons = !polygons_.empty();
  features_.smooth_normals = !corner_normals_.empty();
  for (const auto& m : materials_) {
    features_.mirrors |= glm::length(m.mirror) > 0.0f;
    features_.refraction |= glm::length(m.transmittance) > 0.0f;
    features_.emission |= glm::length(m.emission) > 0.0f;
  }
}

void Scene::add_instances(const io::SceneDesc& desc, const Options& options) {
  // One prototype per object placed (built alone, as the object's own geometry 0: a hit
  // through it names prim = the triangle within the object).
  std::vector<std::int64_t> prototype_of(desc.mesh.objects.size(), -1);
  for (const io::InstanceDesc& in : desc.instances) {
    if (prototype_of[in.object] >= 0) continue;
    const io::ObjectDesc& o = desc.mesh.objects[in.object];
    Accel proto;
    proto.add_triangles(&positions_[0].x, positions_.size(), indices_.data() + 3 * o.first_triangle, o.triangle_count);
    proto.commit(options);
    prototype_of[in.object] = static_cast<std::int64_t>(prototypes_.size());
    prototypes_.push_back(std::move(proto));
  }
  for (const io::InstanceDesc& in : desc.instances) {
    const glm::mat4& m = in.transform;
    std::uint32_t id;
    try {
      id = accel_.add_instance(prototypes_[static_cast<std::size_t>(prototype_of[in.object])], in.rows().data());
    } catch (const Error& e) {
      throw Error("instance '" + in.name + "': " + e.what());
    }
    if (in.mask != kMaskAll) accel_.set_geometry_mask(id, in.mask);
    if (geometry_base_.size() <= id) geometry_base_.resize(id + 1, 0);
    geometry_base_[id] = static_cast<std::uint32_t>(desc.mesh.objects[in.object].first_triangle);
    if (instance_slot_.size() <= id) instance_slot_.resize(id + 1, 0);
    instance_slot_[id] = static_cast<std::uint32_t>(instances_.size());
    const float t = std::max({std::abs(m[3][0]), std::abs(m[3][1]), std::abs(m[3][2])});
    instances_.push_back({m, glm::transpose(glm::inverse(glm::mat3(m))), t});
  }
}

template <bool Smooth>
SurfacePoint Scene::surface_as(const Ray& ray, const Hit& hit) const {
  SurfacePoint s;
  const glm::vec3 dir(ray.dir[0], ray.dir[1], ray.dir[2]);
  const std::size_t tri_count = indices_.size() / 3;
  const std::uint32_t prim = prim_index(hit);
  if (prim < tri_count) {
    glm::vec3 p0, p1, p2;
    triangle_vertices(hit, p0, p1, p2);
    s.p = hit_point(p0, p1, p2, hit.u, hit.v, s.p_error);
    const InstanceShading* instance = hit.inst != kInvalidId ? &instances_[instance_slot_[hit.inst]] : nullptr;
    // Through an instance the ray was carried into the object's space and the vertices
    // out of it, each rounded: widen the bound by that rounding.
    if (instance) s.p_error += core::rounding_gamma(16) * (glm::abs(s.p) + glm::vec3(instance->translation));
    s.ng = glm::normalize(glm::cross(p1 - p0, p2 - p0));
    if (Smooth && !corner_normals_.empty()) {
      const glm::vec3* n = &corner_normals_[3 * prim];
      const float b0 = 1.0f - hit.u - hit.v;
      s.ns = b0 * n[0] + hit.u * n[1] + hit.v * n[2];
      if (instance) s.ns = instance->normal * s.ns;
      const float len = glm::length(s.ns);
      s.ns = len > 0.0f ? s.ns / len : s.ng;
    } else {
      s.ns = s.ng;
    }
    s.material = tri_material_[prim];
  } else {
    const PolygonShading& poly = polygons_[prim - tri_count];
    const glm::vec3 org(ray.org[0], ray.org[1], ray.org[2]);
    const glm::vec3 p = org + hit.t * dir;
    // Project onto the plane: the bound then only covers the plane equation's rounding.
    s.p = p - (glm::dot(poly.normal, p) - poly.d) * poly.normal;
    s.p_error = core::rounding_gamma(8) * (glm::abs(s.p) + glm::vec3(std::abs(poly.d)));
    s.ng = s.ns = poly.normal;
    s.material = poly.material;
  }
  // Face the normals toward the incoming ray; remember which side was hit (for refraction).
  s.front = glm::dot(s.ng, dir) < 0.0f;
  if (!s.front) s.ng = -s.ng;
  if (glm::dot(s.ns, s.ng) < 0.0f) s.ns = -s.ns;
  return s;
}

template SurfacePoint Scene::surface_as<true>(const Ray&, const Hit&) const;
template SurfacePoint Scene::surface_as<false>(const Ray&, const Hit&) const;

SceneFeatures with_closure(const Scene& scene, const io::SceneDesc& desc) {
  core::ClosureCheck closure;
  closure.add_triangles(scene.positions(), scene.indices());
  for (const auto& poly : desc.polygons) closure.add_face(poly.vertices.data(), poly.vertices.size());
  const core::ClosureReport report = closure.finish();
  SceneFeatures f = scene.features();
  f.closed = report.closed();
  f.open_edges = report.unmatched;
  return f;
}

}  // namespace volley::render
