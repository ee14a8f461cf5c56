#include "io/scene_loader.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <optional>
#include <string>
#include <unordered_map>

#include <glm/gtc/matrix_transform.hpp>

#include "io/json_values.h"
#include "io/load_error.h"
#include "io/mesh_append.h"
#include "io/obj_loader.h"
#include "io/ply_loader.h"
#include "io/text_file.h"

namespace volley::io {
namespace {

constexpr int kMaxImageSize = 16384;
constexpr int kMaxSpp = 65536;
constexpr int kMaxDepth = 64;
constexpr std::string_view kScenesPrefix = "${scenes}/";

std::string lower_extension(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

std::string join(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

/// Everything the object readers need besides the JSON itself.
struct Context {
  const std::filesystem::path& file;
  const std::filesystem::path& shared_scenes_dir;
  SceneDesc& scene;
  std::unordered_map<std::string, std::uint32_t> material_of_name;
  std::vector<std::string> material_names;  // in file order, for messages
};

void read_render(const Json& j, const JsonPath& at, RenderSettings& s) {
  check_object(j, at, {"width", "height", "spp", "max_depth", "integrator", "background", "seed"});
  if (j.contains("width")) s.width = static_cast<int>(get_int(j["width"], at["width"], 2, kMaxImageSize));
  if (j.contains("height")) s.height = static_cast<int>(get_int(j["height"], at["height"], 2, kMaxImageSize));
  if (j.contains("spp")) s.spp = static_cast<int>(get_int(j["spp"], at["spp"], 1, kMaxSpp));
  if (j.contains("max_depth")) s.max_depth = static_cast<int>(get_int(j["max_depth"], at["max_depth"], 0, kMaxDepth));
  if (j.contains("integrator")) {
    const std::string& name = get_string(j["integrator"], at["integrator"]);
    if (name != "whitted" && name != "path")
      at["integrator"].fail("expected \"whitted\" or \"path\", found \"" + name + "\"");
    s.integrator = name;
  }
  if (j.contains("background")) s.background = get_colour(j["background"], at["background"], 3.4e38f);
  if (j.contains("seed")) s.seed = get_uint64(j["seed"], at["seed"]);
}

void read_camera(const Json& j, const JsonPath& at, CameraDesc& c) {
  check_object(j, at, {"eye", "look_at", "up", "fov", "u", "v", "w", "f", "window"});
  const bool look_at_form = j.contains("look_at") || j.contains("up") || j.contains("fov");
  const bool notes_form =
      j.contains("u") || j.contains("v") || j.contains("w") || j.contains("f") || j.contains("window");
  if (look_at_form && notes_form)
    at.fail("mixes the look_at form (look_at, up, fov) with the notes' form (u, v, w, f, window); use one");
  if (!look_at_form && !notes_form)
    at.fail("expected either \"look_at\" (with optional \"up\", \"fov\") or the notes' \"u\", \"v\", \"w\" "
            "(with optional \"f\", \"window\")");
  if (!j.contains("eye")) at.fail("missing key \"eye\"");
  c.eye = get_vec3(j["eye"], at["eye"]);

  if (look_at_form) {
    c.kind = CameraDesc::Kind::look_at;
    if (!j.contains("look_at")) at.fail("missing key \"look_at\"");
    c.target = get_vec3(j["look_at"], at["look_at"]);
    if (j.contains("up")) c.up = get_vec3(j["up"], at["up"]);
    if (j.contains("fov")) c.fov_deg = get_float(j["fov"], at["fov"], 0.0f, 180.0f);
    if (c.fov_deg <= 0.0f || c.fov_deg >= 180.0f)
      at["fov"].fail("expected a vertical field of view in degrees, strictly between 0 and 180");
    const glm::vec3 view = c.target - c.eye;
    if (glm::length(view) == 0.0f) at["look_at"].fail("must differ from \"eye\"");
    if (glm::length(glm::cross(glm::normalize(view), c.up)) < 1e-6f)
      at["up"].fail("must not be zero or parallel to the view direction (look_at - eye)");
    return;
  }

  c.kind = CameraDesc::Kind::notes;
  for (const char* axis : {"u", "v", "w"})
    if (!j.contains(axis)) at.fail(std::string("missing key \"") + axis + "\" (the notes' form needs u, v and w)");
  c.u = get_vec3(j["u"], at["u"]);
  c.v = get_vec3(j["v"], at["v"]);
  c.w = get_vec3(j["w"], at["w"]);
  const float scale = glm::length(c.u) * glm::length(c.v) * glm::length(c.w);
  if (!(std::fabs(glm::dot(glm::cross(c.u, c.v), c.w)) > 1e-6f * scale))
    at.fail("u, v and w must be non-zero and linearly independent");
  if (j.contains("f")) c.f = get_float(j["f"], at["f"]);
  if (!(c.f > 0.0f)) at["f"].fail("expected a focal distance greater than 0");
  if (j.contains("window")) {
    const Json& w = j["window"];
    const JsonPath wat = at["window"];
    check_object(w, wat, {"left", "right", "top", "bottom"});
    for (const char* side : {"left", "right", "top", "bottom"})
      if (!w.contains(side)) wat.fail(std::string("missing key \"") + side + "\"");
    c.wl = get_float(w["left"], wat["left"]);
    c.wr = get_float(w["right"], wat["right"]);
    c.wt = get_float(w["top"], wat["top"]);
    c.wb = get_float(w["bottom"], wat["bottom"]);
    if (!(c.wl < c.wr)) wat.fail("expected left < right");
    if (!(c.wb < c.wt)) wat.fail("expected bottom < top");
  }
}

void read_materials(const Json& j, const JsonPath& at, Context& ctx) {
  if (!j.is_object()) at.fail("expected an object mapping material names to materials, found " + describe(j));
  for (const auto& [name, m] : j.items()) {
    const JsonPath mat = at[name];
    if (name.empty()) at.fail("a material name must not be empty");
    check_object(m, mat,
                 {"ambient", "diffuse", "specular", "shininess", "mirror", "transmittance", "ior", "emission"});
    Material out;
    out.name = name;
    if (m.contains("ambient")) out.ambient = get_colour(m["ambient"], mat["ambient"], 1.0f);
    if (m.contains("diffuse")) out.diffuse = get_colour(m["diffuse"], mat["diffuse"], 1.0f);
    if (m.contains("specular")) out.specular = get_colour(m["specular"], mat["specular"], 1.0f);
    if (m.contains("shininess")) out.shininess = get_float(m["shininess"], mat["shininess"], 0.0f);
    if (m.contains("mirror")) out.mirror = get_colour(m["mirror"], mat["mirror"], 1.0f);
    if (m.contains("transmittance"))
      out.transmittance = get_colour(m["transmittance"], mat["transmittance"], 1.0f);
    if (m.contains("ior")) {
      out.ior = get_float(m["ior"], mat["ior"], 0.0f);
      if (!(out.ior > 0.0f)) mat["ior"].fail("expected an index of refraction greater than 0");
    }
    if (m.contains("emission")) out.emission = get_colour(m["emission"], mat["emission"], 3.4e38f);
    ctx.material_of_name.emplace(name, static_cast<std::uint32_t>(ctx.scene.materials.size()));
    ctx.material_names.push_back(name);
    ctx.scene.materials.push_back(std::move(out));
  }
}

void read_lights(const Json& j, const JsonPath& at, SceneDesc& scene) {
  check_array(j, at);
  for (std::size_t i = 0; i < j.size(); ++i) {
    const JsonPath light = at[i];
    check_object(j[i], light, {"position", "intensity"});
    if (!j[i].contains("position")) light.fail("missing key \"position\"");
    PointLight l;
    l.position = get_vec3(j[i]["position"], light["position"]);
    if (j[i].contains("intensity")) l.intensity = get_colour(j[i]["intensity"], light["intensity"], 3.4e38f);
    scene.lights.push_back(l);
  }
}

/// Scale, then rotate, then translate: M = T * R * S.
glm::mat4 read_transform(const Json& j, const JsonPath& at) {
  check_object(j, at, {"scale", "rotate", "translate"});
  glm::vec3 scale(1.0f);
  if (j.contains("scale")) {
    const Json& s = j["scale"];
    if (s.is_number()) {
      scale = glm::vec3(get_float(s, at["scale"]));
    } else if (s.is_array()) {
      scale = get_vec3(s, at["scale"]);
    } else {
      at["scale"].fail("expected a number or an array of 3 numbers, found " + describe(s));
    }
    if (scale.x == 0.0f || scale.y == 0.0f || scale.z == 0.0f)
      at["scale"].fail("expected non-zero scale factors, found " + s.dump());
  }
  glm::mat4 rotate(1.0f);
  if (j.contains("rotate")) {
    const Json& r = j["rotate"];
    const JsonPath rat = at["rotate"];
    check_object(r, rat, {"axis", "degrees"});
    if (!r.contains("axis")) rat.fail("missing key \"axis\"");
    if (!r.contains("degrees")) rat.fail("missing key \"degrees\"");
    const glm::vec3 axis = get_vec3(r["axis"], rat["axis"]);
    if (!(glm::length(axis) > 0.0f)) rat["axis"].fail("expected a non-zero axis");
    const float degrees = get_float(r["degrees"], rat["degrees"]);
    rotate = glm::rotate(glm::mat4(1.0f), glm::radians(degrees), glm::normalize(axis));
  }
  glm::vec3 translate(0.0f);
  if (j.contains("translate")) translate = get_vec3(j["translate"], at["translate"]);
  return glm::translate(glm::mat4(1.0f), translate) * rotate * glm::scale(glm::mat4(1.0f), scale);
}

std::optional<std::uint32_t> read_material_name(const Json& obj, const JsonPath& at, const Context& ctx) {
  if (!obj.contains("material")) return std::nullopt;
  const std::string& name = get_string(obj["material"], at["material"]);
  const auto it = ctx.material_of_name.find(name);
  if (it == ctx.material_of_name.end())
    at["material"].fail("unknown material \"" + name + "\"" +
                        (ctx.material_names.empty() ? std::string(" (the scene defines no \"materials\")")
                                                    : " (defined: " + join(ctx.material_names) + ")"));
  return it->second;
}

std::filesystem::path resolve_mesh_file(const std::string& name, const JsonPath& at, const Context& ctx) {
  if (name.rfind(kScenesPrefix, 0) == 0) {
    const std::string rest = name.substr(kScenesPrefix.size());
    if (ctx.shared_scenes_dir.empty())
      at.fail("shared mesh \"" + name +
              "\" needs the shared scenes folder: pass --scenes DIR or set VOLLEY_SCENES");
    const std::filesystem::path path = ctx.shared_scenes_dir / rest;
    if (!std::filesystem::exists(path))
      at.fail("shared mesh \"" + name + "\" not found (looked for " + path.string() +
              "): get the benchmark meshes with scenes/fetch, or pass --scenes DIR or set VOLLEY_SCENES to the "
              "folder that holds them");
    return path;
  }
  if (name.find("${") != std::string::npos)
    at.fail("unknown variable in \"" + name + "\" (the only one is ${scenes}/ at the start)");
  std::filesystem::path path(name);
  if (path.is_relative()) path = ctx.file.parent_path() / path;
  if (!std::filesystem::exists(path))
    at.fail("mesh file \"" + name + "\" not found (looked for " + path.string() +
            "; relative paths start at the scene file's folder)");
  return path;
}

void read_mesh(const Json& obj, const JsonPath& at, const glm::mat4& transform, Context& ctx) {
  if (!obj.contains("file")) at.fail("missing key \"file\"");
  const std::string& name = get_string(obj["file"], at["file"]);
  const std::filesystem::path path = resolve_mesh_file(name, at["file"], ctx);
  const std::optional<std::uint32_t> material = read_material_name(obj, at, ctx);
  const std::string ext = lower_extension(path);
  if (ext == ".obj") {
    load_obj(path, transform, material, ctx.scene);
  } else if (ext == ".ply") {
    load_ply(path, transform, material, ctx.scene);
  } else {
    at["file"].fail("unsupported mesh format \"" + ext + "\" (expected .obj or .ply)");
  }
}

void read_triangles(const Json& obj, const JsonPath& at, const glm::mat4& transform, Context& ctx) {
  if (!obj.contains("vertices")) at.fail("missing key \"vertices\"");
  const Json& vs = obj["vertices"];
  check_array(vs, at["vertices"], 3);
  std::vector<glm::vec3> vertices;
  for (std::size_t i = 0; i < vs.size(); ++i) {
    const glm::vec3 p = glm::vec3(transform * glm::vec4(get_vec3(vs[i], at["vertices"][i]), 1.0f));
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      at["vertices"][i].fail("not finite after the object transform");
    vertices.push_back(p);
  }
  std::vector<std::uint32_t> indices;
  if (obj.contains("indices")) {
    const Json& is = obj["indices"];
    check_array(is, at["indices"], 1);
    for (std::size_t t = 0; t < is.size(); ++t) {
      const JsonPath tri = at["indices"][t];
      if (!is[t].is_array() || is[t].size() != 3)
        tri.fail("expected an array of 3 vertex indices, found " + describe(is[t]));
      for (std::size_t k = 0; k < 3; ++k) {
        if (is[t][k].is_number() && is[t][k].get<double>() >= static_cast<double>(vertices.size()))
          tri[k].fail("index " + describe(is[t][k]) + " is out of range (the object has " +
                      std::to_string(vertices.size()) + " vertices, indices start at 0)");
        indices.push_back(static_cast<std::uint32_t>(
            get_int(is[t][k], tri[k], 0, static_cast<std::int64_t>(vertices.size()) - 1)));
      }
    }
  } else {
    if (vertices.size() % 3 != 0)
      at["vertices"].fail("without \"indices\" every 3 vertices form a triangle, but there are " +
                          std::to_string(vertices.size()));
    for (std::uint32_t i = 0; i < vertices.size(); ++i) indices.push_back(i);
  }

  const std::uint32_t material = read_material_name(obj, at, ctx).value_or(~0u);
  MeshDesc& mesh = ctx.scene.mesh;
  const auto base = static_cast<std::uint32_t>(mesh.positions.size());
  const std::uint32_t m = material != ~0u ? material : ensure_default_material(ctx.scene.materials);
  mesh.positions.insert(mesh.positions.end(), vertices.begin(), vertices.end());
  for (const std::uint32_t i : indices) mesh.indices.push_back(base + i);
  mesh.material.insert(mesh.material.end(), indices.size() / 3, m);
  if (!mesh.corner_normals.empty()) complete_corner_normals(mesh);
}

void read_polygon(const Json& obj, const JsonPath& at, const glm::mat4& transform, Context& ctx) {
  if (!obj.contains("vertices")) at.fail("missing key \"vertices\"");
  const Json& vs = obj["vertices"];
  if (vs.is_array() && vs.size() < 3)
    at["vertices"].fail("a polygon needs at least 3 vertices, found " + std::to_string(vs.size()));
  check_array(vs, at["vertices"], 3);
  PolygonDesc polygon;
  polygon.name = obj.contains("name") ? get_string(obj["name"], at["name"]) : at.str();
  for (std::size_t i = 0; i < vs.size(); ++i) {
    const glm::vec3 p = glm::vec3(transform * glm::vec4(get_vec3(vs[i], at["vertices"][i]), 1.0f));
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      at["vertices"][i].fail("not finite after the object transform");
    polygon.vertices.push_back(p);
  }
  const std::optional<std::uint32_t> material = read_material_name(obj, at, ctx);
  polygon.material = material ? *material : ensure_default_material(ctx.scene.materials);
  ctx.scene.polygons.push_back(std::move(polygon));
}

void read_objects(const Json& j, const JsonPath& at, Context& ctx) {
  check_array(j, at);
  for (std::size_t i = 0; i < j.size(); ++i) {
    const Json& obj = j[i];
    const JsonPath oat = at[i];
    if (!obj.is_object()) oat.fail("expected an object, found " + describe(obj));
    if (!obj.contains("type")) oat.fail("missing key \"type\" (mesh, triangles, polygon or instance)");
    const std::string& type = get_string(obj["type"], oat["type"]);
    if (type == "mesh") {
      check_object(obj, oat, {"type", "name", "file", "material", "transform", "mask"});
    } else if (type == "triangles") {
      check_object(obj, oat, {"type", "name", "vertices", "indices", "material", "transform", "mask"});
    } else if (type == "polygon") {
      check_object(obj, oat, {"type", "name", "vertices", "material", "transform", "mask"});
    } else if (type == "instance") {
      check_object(obj, oat, {"type", "name", "of", "transform", "mask"});
    } else {
      oat["type"].fail("unknown object type \"" + type + "\" (expected mesh, triangles, polygon or instance)");
    }
    if (obj.contains("name")) get_string(obj["name"], oat["name"]);
    const std::uint32_t mask =
        obj.contains("mask") ? static_cast<std::uint32_t>(get_int(obj["mask"], oat["mask"], 0, 0xffffffffll)) : 0xffffffffu;
    const glm::mat4 transform =
        obj.contains("transform") ? read_transform(obj["transform"], oat["transform"]) : glm::mat4(1.0f);
    MeshDesc& mesh = ctx.scene.mesh;
    if (type == "instance") {
      if (!obj.contains("of")) oat.fail("missing key \"of\" (the name of a mesh or triangles object above)");
      const std::string& of = get_string(obj["of"], oat["of"]);
      const auto it = std::find_if(mesh.objects.begin(), mesh.objects.end(),
                                   [&](const ObjectDesc& o) { return o.name == of; });
      if (it == mesh.objects.end())
        oat["of"].fail("no mesh or triangles object named \"" + of + "\" above this one (an instance places an "
                       "object defined before it, by its \"name\")");
      ctx.scene.instances.push_back({obj.contains("name") ? obj["name"].get<std::string>() : oat.str(),
                                     static_cast<std::size_t>(it - mesh.objects.begin()), transform, mask});
      continue;
    }
    const std::size_t first = mesh.triangle_count();
    if (type == "mesh") read_mesh(obj, oat, transform, ctx);
    if (type == "triangles") read_triangles(obj, oat, transform, ctx);
    if (type == "polygon") {
      read_polygon(obj, oat, transform, ctx);
      ctx.scene.polygons.back().mask = mask;
    } else {
      mesh.objects.push_back({obj.contains("name") ? obj["name"].get<std::string>() : oat.str(), first,
                              mesh.triangle_count() - first, mask});
    }
  }
}

SceneDesc load_json_scene(const std::filesystem::path& file, const std::filesystem::path& shared_scenes_dir) {
  const Json root = parse_json(file, read_text_file(file));
  const JsonPath at(file, "(top level)");
  check_object(root, at, {"camera", "render", "materials", "lights", "objects"});

  SceneDesc scene;
  scene.source = file.string();
  Context ctx{file, shared_scenes_dir, scene, {}, {}};
  if (root.contains("render")) read_render(root["render"], at["render"], scene.settings);
  if (root.contains("camera")) {
    read_camera(root["camera"], at["camera"], scene.camera);
    scene.has_camera = true;
  }
  if (root.contains("materials")) read_materials(root["materials"], at["materials"], ctx);
  if (root.contains("lights")) read_lights(root["lights"], at["lights"], scene);
  if (root.contains("objects")) read_objects(root["objects"], at["objects"], ctx);
  return scene;
}

}  // namespace

SceneDesc load_scene(const std::filesystem::path& file, const std::filesystem::path& shared_scenes_dir) {
  std::error_code ec;
  const auto status = std::filesystem::status(file, ec);
  if (!std::filesystem::exists(status)) throw LoadError(file, "file not found");
  if (std::filesystem::is_directory(status))
    throw LoadError(file, "is a directory, expected a scene file (.json) or a mesh (.obj, .ply)");
  const std::string ext = lower_extension(file);
  SceneDesc scene;
  if (ext == ".json") {
    scene = load_json_scene(file, shared_scenes_dir);
  } else if (ext == ".obj" || ext == ".ply") {
    scene.source = file.string();
    if (ext == ".obj") load_obj(file, glm::mat4(1.0f), std::nullopt, scene);
    else load_ply(file, glm::mat4(1.0f), std::nullopt, scene);
    scene.mesh.objects.push_back({file.filename().string(), 0, scene.mesh.triangle_count()});
  } else {
    throw LoadError(file, "unknown scene file type \"" + ext + "\" (expected .json, .obj or .ply)");
  }
  if (scene.mesh.triangle_count() == 0 && scene.polygons.empty())
    throw LoadError(file, ext == ".json" ? "scene has no geometry: \"objects\" holds no triangles or polygons"
                                         : "scene has no geometry: the mesh has no faces");
  if (scene.materials.empty()) ensure_default_material(scene.materials);
  return scene;
}

}  // namespace volley::io
