#include "io/obj_loader.h"

#include <tiny_obj_loader.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include "io/load_error.h"
#include "io/mesh_append.h"
#include "io/text_file.h"

namespace volley::io {
namespace {

constexpr std::uint32_t kNone = 0xffffffffu;

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

const char* skip_blanks(const char* p, const char* e) {
  while (p < e && is_blank(*p)) ++p;
  return p;
}

const char* token_end(const char* p, const char* e) {
  while (p < e && !is_blank(*p)) ++p;
  return p;
}

std::string quoted_token(const char* p, const char* e) {
  const char* t = token_end(p, e);
  constexpr std::size_t kMax = 32;
  std::string s(p, std::min<std::size_t>(static_cast<std::size_t>(t - p), kMax));
  if (static_cast<std::size_t>(t - p) > kMax) s += "...";
  return '"' + s + '"';
}

/// A positive index that pointed past the vertices defined so far when it was read;
/// valid only if the rest of the file defines enough of them.
struct ForwardRef {
  std::uint64_t index;  // 1-based, as written
  std::size_t line;
  std::size_t column;
  bool normal;
};

/// One pass over the OBJ text, straight into flat arrays; nothing is committed to
/// the scene until the whole file parsed and checked.
class ObjParser {
 public:
  ObjParser(const std::filesystem::path& file, std::string_view text) : file_(file), text_(text) {}

  void parse();

  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;
  std::vector<std::uint32_t> corner_position;  ///< 3 per triangle, 0-based
  bool has_normals = false;                    ///< some face corner references a vn
  std::vector<std::uint32_t> corner_normal;    ///< 3 per triangle (kNone: no vn) if has_normals
  std::vector<std::uint32_t> triangle_slot;    ///< 1 per triangle: index into slot_names or kNone
  std::vector<std::string> slot_names;         ///< usemtl names in order of first use
  struct Library {
    std::string name;
    std::size_t line;
  };
  std::vector<Library> libraries;  ///< mtllib file names as written
  std::vector<ForwardRef> forward_refs;

 private:
  struct Corner {
    std::uint32_t position;
    std::uint32_t normal;
  };

  [[noreturn]] void fail(const char* at, const std::string& what) const {
    throw LoadError(file_, line_number_, static_cast<std::size_t>(at - line_begin_) + 1, what);
  }

  void parse_line(const char* p, const char* e);
  glm::vec3 parse_vec3(const char* p, const char* e, const char* what);
  float parse_float(const char*& p, const char* e, const char* what);
  long long parse_index(const char*& p, const char* e, const char* what);
  std::uint32_t resolve(long long index, std::size_t defined, const char* at, bool normal);
  void parse_face(const char* p, const char* e);

  const std::filesystem::path& file_;
  std::string_view text_;
  const char* line_begin_ = nullptr;
  const char* statement_ = nullptr;  // keyword of the current line
  std::size_t line_number_ = 0;
  std::uint32_t current_slot_ = kNone;
  std::unordered_map<std::string, std::uint32_t> slot_of_name_;
  std::vector<Corner> face_;  // reused for every face
};

void ObjParser::parse() {
  const char* p = text_.data();
  const char* const end = p + text_.size();
  while (p < end) {
    const char* nl = static_cast<const char*>(std::memchr(p, '\n', static_cast<std::size_t>(end - p)));
    const char* line_end = nl ? nl : end;
    ++line_number_;
    line_begin_ = p;
    parse_line(p, line_end);
    p = nl ? nl + 1 : end;
  }
}

void ObjParser::parse_line(const char* p, const char* e) {
  p = skip_blanks(p, e);
  if (p == e || *p == '#') return;
  const char* k = p;
  statement_ = p;
  p = token_end(p, e);
  const std::string_view keyword(k, static_cast<std::size_t>(p - k));
  if (keyword == "v") {
    positions.push_back(parse_vec3(p, e, "vertex coordinate"));
  } else if (keyword == "vn") {
    normals.push_back(parse_vec3(p, e, "normal coordinate"));
  } else if (keyword == "f") {
    parse_face(p, e);
  } else if (keyword == "usemtl") {
    p = skip_blanks(p, e);
    const char* name_end = e;
    while (name_end > p && is_blank(name_end[-1])) --name_end;
    if (p == name_end) fail(p, "expected a material name after usemtl");
    std::string name(p, name_end);
    const auto [it, inserted] = slot_of_name_.try_emplace(name, static_cast<std::uint32_t>(slot_names.size()));
    if (inserted) slot_names.push_back(std::move(name));
    current_slot_ = it->second;
  } else if (keyword == "mtllib") {
    for (p = skip_blanks(p, e); p < e && *p != '#'; p = skip_blanks(p, e)) {
      const char* t = token_end(p, e);
      libraries.push_back({std::string(p, t), line_number_});
      p = t;
    }
  }
  // Everything else (vt, vp, g, o, s, l, p, mg, curves, ...) does not affect triangles.
}

glm::vec3 ObjParser::parse_vec3(const char* p, const char* e, const char* what) {
  glm::vec3 v;
  v.x = parse_float(p, e, what);
  v.y = parse_float(p, e, what);
  v.z = parse_float(p, e, what);
  return v;  // a w component or vertex colours may follow; they are ignored
}

float ObjParser::parse_float(const char*& p, const char* e, const char* what) {
  p = skip_blanks(p, e);
  if (p == e || *p == '#') fail(p, std::string("expected a ") + what + " (x y z), found the end of the line");
  const char* start = p;
  const char* digits = (*p == '+') ? p + 1 : p;  // from_chars rejects a leading '+'
  float value = 0.0f;
  auto [next, ec] = std::from_chars(digits, e, value);
  if (ec == std::errc::result_out_of_range) {
    // Underflow is harmless (the value is as good as 0); overflow is an error.
    const std::string token(digits, token_end(digits, e));
    const double d = std::strtod(token.c_str(), nullptr);
    if (!(std::fabs(d) <= static_cast<double>(std::numeric_limits<float>::max())))
      fail(start, std::string("expected a ") + what + ", found " + quoted_token(start, e) +
                      " (out of float range)");
    value = static_cast<float>(d);
    ec = std::errc();
  }
  if (ec != std::errc() || (next < e && !is_blank(*next) && *next != '#'))
    fail(start, std::string("expected a ") + what + ", found " + quoted_token(start, e));
  if (!std::isfinite(value))
    fail(start, std::string("expected a finite ") + what + ", found " + quoted_token(start, e));
  p = next;
  return value;
}

long long ObjParser::parse_index(const char*& p, const char* e, const char* what) {
  const char* digits = (p < e && *p == '+') ? p + 1 : p;
  long long value = 0;
  const auto [next, ec] = std::from_chars(digits, e, value);
  if (ec != std::errc()) fail(p, std::string("expected ") + what + ", found " + quoted_token(p, e));
  p = next;
  return value;
}

std::uint32_t ObjParser::resolve(long long index, std::size_t defined, const char* at, bool normal) {
  const std::string kind = normal ? "normal" : "vertex";
  const std::string plural = normal ? "normals" : "vertices";
  if (index == 0)
    fail(at, kind + " index 0 is not valid: OBJ indices start at 1 (negative ones count back from the last " + kind +
                 ")");
  if (index < 0) {
    const auto back = static_cast<unsigned long long>(-(index + 1)) + 1;
    if (back > defined)
      fail(at, "relative " + kind + " index " + std::to_string(index) + " is out of range: only " +
                   std::to_string(defined) + " " + plural + " are defined above this line");
    return static_cast<std::uint32_t>(defined - back);
  }
  if (static_cast<unsigned long long>(index) > kNone - 1ull)
    fail(at, kind + " index " + std::to_string(index) + " is out of range");
  if (static_cast<std::size_t>(index) > defined)
    forward_refs.push_back({static_cast<std::uint64_t>(index), line_number_,
                            static_cast<std::size_t>(at - line_begin_) + 1, normal});
  return static_cast<std::uint32_t>(index - 1);
}

void ObjParser::parse_face(const char* p, const char* e) {
  face_.clear();
  for (p = skip_blanks(p, e); p < e && *p != '#'; p = skip_blanks(p, e)) {
    const char* at = p;
    Corner c{kNone, kNone};
    c.position = resolve(parse_index(p, e, "a vertex index"), positions.size(), at, false);
    if (p < e && *p == '/') {
      ++p;
      if (p < e && *p != '/' && !is_blank(*p)) parse_index(p, e, "a texture coordinate index");
      if (p < e && *p == '/') {
        ++p;
        const char* n_at = p;
        c.normal = resolve(parse_index(p, e, "a normal index"), normals.size(), n_at, true);
      }
    }
    if (p < e && !is_blank(*p) && *p != '#')
      fail(at, "expected a face corner v, v/vt, v//vn or v/vt/vn, found " + quoted_token(at, e));
    if (face_.size() == kMaxFaceCorners)
      fail(at, "a face has more than " + std::to_string(kMaxFaceCorners) + " corners (the limit of one face)");
    face_.push_back(c);
  }
  if (face_.size() < 3)
    fail(statement_, "a face needs at least 3 vertices, found " + std::to_string(face_.size()));

  if (!has_normals) {
    for (const Corner& c : face_) has_normals |= c.normal != kNone;
    if (has_normals) corner_normal.assign(corner_position.size(), kNone);  // first face with normals
  }
  for (std::size_t i = 1; i + 1 < face_.size(); ++i) {
    for (const Corner& c : {face_[0], face_[i], face_[i + 1]}) {
      corner_position.push_back(c.position);
      if (has_normals) corner_normal.push_back(c.normal);
    }
    triangle_slot.push_back(current_slot_);
  }
}

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
                                               const std::vector<ObjParser::Library>& libraries) {
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

/// Material index of every triangle: the override, or the MTL material its usemtl
/// names (appended to `materials` on first use), or the default material.
std::vector<std::uint32_t> assign_materials(const std::filesystem::path& file, const ObjParser& obj,
                                            std::optional<std::uint32_t> material_override,
                                            std::vector<Material>& materials) {
  const std::size_t triangles = obj.triangle_slot.size();
  if (material_override) return std::vector<std::uint32_t>(triangles, *material_override);

  const std::map<std::string, Material> library = read_libraries(file, obj.libraries);
  std::vector<std::uint32_t> material_of_slot(obj.slot_names.size(), kNone);
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
  std::uint32_t fallback = kNone;
  for (std::size_t t = 0; t < triangles; ++t) {
    const std::uint32_t slot = obj.triangle_slot[t];
    std::uint32_t m = slot == kNone ? kNone : material_of_slot[slot];
    if (m == kNone) {
      if (fallback == kNone) fallback = ensure_default_material(materials);
      m = fallback;
    }
    result[t] = m;
  }
  return result;
}

}  // namespace

void load_obj(const std::filesystem::path& file, const glm::mat4& transform,
              std::optional<std::uint32_t> material_override, SceneDesc& into) {
  if (material_override && *material_override >= into.materials.size())
    throw std::invalid_argument("load_obj: material_override " + std::to_string(*material_override) +
                                " is not an index into the scene's " + std::to_string(into.materials.size()) +
                                " materials");
  const std::string text = read_text_file(file);
  ObjParser obj(file, text);
  obj.parse();

  for (const ForwardRef& ref : obj.forward_refs) {
    const std::size_t defined = ref.normal ? obj.normals.size() : obj.positions.size();
    if (ref.index > defined)
      throw LoadError(file, ref.line, ref.column,
                      std::string(ref.normal ? "normal" : "vertex") + " index " + std::to_string(ref.index) +
                          " is out of range: the file has " + std::to_string(defined) +
                          (ref.normal ? " normals" : " vertices"));
  }

  MeshDesc& mesh = into.mesh;
  const std::size_t base = mesh.positions.size();
  if (base + obj.positions.size() >= kNone)
    throw LoadError(file, "too many vertices in the scene (more than 2^32 - 1)");

  // Transform positions (the identity is skipped so that coordinates stay bit-exact).
  std::vector<glm::vec3>& positions = obj.positions;
  if (transform != glm::mat4(1.0f)) {
    for (std::size_t i = 0; i < positions.size(); ++i) {
      positions[i] = glm::vec3(transform * glm::vec4(positions[i], 1.0f));
      if (!std::isfinite(positions[i].x) || !std::isfinite(positions[i].y) || !std::isfinite(positions[i].z))
        throw LoadError(file, "vertex " + std::to_string(i + 1) + " is not finite after the object transform");
    }
  }

  // Everything below only appends; build the material indices first, since reading
  // the MTL is the last step that may throw, then commit.
  std::vector<Material> materials = into.materials;
  std::vector<std::uint32_t> triangle_material = assign_materials(file, obj, material_override, materials);

  // Corner normals of the new triangles (empty when the file has no vn references).
  std::vector<glm::vec3> new_normals;
  const std::size_t triangles = obj.triangle_slot.size();
  if (obj.has_normals) {
    const glm::mat3 normal_matrix = glm::transpose(glm::inverse(glm::mat3(transform)));
    std::vector<glm::vec3> unit(obj.normals.size());
    for (std::size_t i = 0; i < unit.size(); ++i) {
      const glm::vec3 n = normal_matrix * obj.normals[i];
      const float len = glm::length(n);
      unit[i] = (len > 0.0f && std::isfinite(len)) ? n / len : glm::vec3(0.0f);  // 0: use the face normal
    }
    new_normals.resize(3 * triangles);
    for (std::size_t t = 0; t < triangles; ++t) {
      glm::vec3 corner[3];
      glm::vec3 any_corner(0.0f);
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t n = obj.corner_normal[3 * t + k];
        corner[k] = n == kNone ? glm::vec3(0.0f) : unit[n];
        if (corner[k] != glm::vec3(0.0f)) any_corner = corner[k];
      }
      if (corner[0] == glm::vec3(0.0f) || corner[1] == glm::vec3(0.0f) || corner[2] == glm::vec3(0.0f)) {
        // Fallback for corners without a usable vn: the face normal, else (zero-area
        // triangle) another corner's normal, else +z. Such triangles are never hit.
        glm::vec3 fallback = geometric_normal(positions[obj.corner_position[3 * t]],
                                              positions[obj.corner_position[3 * t + 1]],
                                              positions[obj.corner_position[3 * t + 2]]);
        if (fallback == glm::vec3(0.0f)) fallback = any_corner;
        if (fallback == glm::vec3(0.0f)) fallback = glm::vec3(0, 0, 1);
        for (glm::vec3& c : corner)
          if (c == glm::vec3(0.0f)) c = fallback;
      }
      for (int k = 0; k < 3; ++k) new_normals[3 * t + k] = corner[k];
    }
  }

  // Commit (allocation failure aside, nothing below throws).
  into.materials = std::move(materials);
  if (!new_normals.empty()) complete_corner_normals(mesh);  // earlier triangles without normals
  const bool mesh_has_normals = !mesh.corner_normals.empty();
  mesh.positions.insert(mesh.positions.end(), positions.begin(), positions.end());
  mesh.indices.reserve(mesh.indices.size() + obj.corner_position.size());
  for (const std::uint32_t i : obj.corner_position) mesh.indices.push_back(static_cast<std::uint32_t>(base + i));
  mesh.material.insert(mesh.material.end(), triangle_material.begin(), triangle_material.end());
  if (!new_normals.empty())
    mesh.corner_normals.insert(mesh.corner_normals.end(), new_normals.begin(), new_normals.end());
  else if (mesh_has_normals)
    complete_corner_normals(mesh);
}

}  // namespace volley::io
