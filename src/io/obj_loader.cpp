#include "io/obj_loader.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include "io/load_error.h"
#include "io/mesh_append.h"
#include "io/obj_materials.h"
#include "io/text_file.h"

namespace volley::io {
namespace {

constexpr std::uint32_t kNone = kNoMaterialSlot;  // also: a corner without a vn

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
  std::vector<MtlLibrary> libraries;  ///< mtllib file names as written
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

/// Forward references (an index past the vertices or normals defined when it was read)
/// that the rest of the file did not make valid.
void check_forward_refs(const std::filesystem::path& file, const ObjParser& obj) {
  for (const ForwardRef& ref : obj.forward_refs) {
    const std::size_t defined = ref.normal ? obj.normals.size() : obj.positions.size();
    if (ref.index > defined)
      throw LoadError(file, ref.line, ref.column,
                      std::string(ref.normal ? "normal" : "vertex") + " index " + std::to_string(ref.index) +
                          " is out of range: the file has " + std::to_string(defined) +
                          (ref.normal ? " normals" : " vertices"));
  }
}

/// The file's vn normals moved by the transform's normal matrix, unit length; 0 where a
/// normal is zero or not finite (its corners take the face normal).
std::vector<glm::vec3> unit_normals(const ObjParser& obj, const glm::mat4& transform) {
  const glm::mat3 normal_matrix = glm::transpose(glm::inverse(glm::mat3(transform)));
  std::vector<glm::vec3> unit(obj.normals.size());
  for (std::size_t i = 0; i < unit.size(); ++i) {
    const glm::vec3 n = normal_matrix * obj.normals[i];
    const float len = glm::length(n);
    unit[i] = (len > 0.0f && std::isfinite(len)) ? n / len : glm::vec3(0.0f);
  }
  return unit;
}

/// Corner normals of the new triangles (empty when the file has no vn references). Corners
/// without a usable vn take the face normal, else (zero-area triangle) another corner's
/// normal, else +z; such triangles are never hit.
std::vector<glm::vec3> corner_normals(const ObjParser& obj, const glm::mat4& transform) {
  if (!obj.has_normals) return {};
  const std::vector<glm::vec3> unit = unit_normals(obj, transform);
  const std::size_t triangles = obj.triangle_slot.size();
  std::vector<glm::vec3> normals(3 * triangles);
  for (std::size_t t = 0; t < triangles; ++t) {
    glm::vec3* corner = &normals[3 * t];
    glm::vec3 any_corner(0.0f);
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t n = obj.corner_normal[3 * t + k];
      corner[k] = n == kNone ? glm::vec3(0.0f) : unit[n];
      if (corner[k] != glm::vec3(0.0f)) any_corner = corner[k];
    }
    if (corner[0] != glm::vec3(0.0f) && corner[1] != glm::vec3(0.0f) && corner[2] != glm::vec3(0.0f)) continue;
    const std::uint32_t* v = &obj.corner_position[3 * t];
    glm::vec3 fallback = geometric_normal(obj.positions[v[0]], obj.positions[v[1]], obj.positions[v[2]]);
    if (fallback == glm::vec3(0.0f)) fallback = any_corner;
    if (fallback == glm::vec3(0.0f)) fallback = glm::vec3(0, 0, 1);
    for (int k = 0; k < 3; ++k)
      if (corner[k] == glm::vec3(0.0f)) corner[k] = fallback;
  }
  return normals;
}

/// The parsed triangles appended to the scene's mesh (allocation failure aside, nothing
/// here throws).
void commit(const ObjParser& obj, const std::vector<std::uint32_t>& triangle_material,
            const std::vector<glm::vec3>& new_normals, MeshDesc& mesh) {
  const std::size_t base = mesh.positions.size();
  if (!new_normals.empty()) complete_corner_normals(mesh);  // earlier triangles without normals
  const bool mesh_has_normals = !mesh.corner_normals.empty();
  mesh.positions.insert(mesh.positions.end(), obj.positions.begin(), obj.positions.end());
  mesh.indices.reserve(mesh.indices.size() + obj.corner_position.size());
  for (const std::uint32_t i : obj.corner_position) mesh.indices.push_back(static_cast<std::uint32_t>(base + i));
  mesh.material.insert(mesh.material.end(), triangle_material.begin(), triangle_material.end());
  if (!new_normals.empty())
    mesh.corner_normals.insert(mesh.corner_normals.end(), new_normals.begin(), new_normals.end());
  else if (mesh_has_normals)
    complete_corner_normals(mesh);
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
  check_forward_refs(file, obj);
  if (into.mesh.positions.size() + obj.positions.size() >= kNone)
    throw LoadError(file, "too many vertices in the scene (more than 2^32 - 1)");
  transform_positions(file, transform, obj.positions, 1);

  // Everything below only appends; the material indices come first, since reading the
  // MTL is the last step that may throw.
  std::vector<Material> materials = into.materials;
  const std::vector<std::uint32_t> triangle_material = obj_triangle_materials(
      file, {obj.libraries, obj.slot_names, obj.triangle_slot}, material_override, materials);
  const std::vector<glm::vec3> new_normals = corner_normals(obj, transform);
  into.materials = std::move(materials);
  commit(obj, triangle_material, new_normals, into.mesh);
}

}  // namespace volley::io
