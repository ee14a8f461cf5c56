#include "io/ply_loader.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "io/load_error.h"
#include "io/mesh_append.h"
#include "io/text_file.h"

namespace volley::io {
namespace {

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f'; }

bool is_scalar_type(std::string_view t) {
  for (const char* known : {"char", "uchar", "short", "ushort", "int", "uint", "float", "double", "int8", "uint8",
                            "int16", "uint16", "int32", "uint32", "float32", "float64"})
    if (t == known) return true;
  return false;
}

struct Property {
  std::string name;
  bool is_list = false;
};

struct Element {
  std::string name;
  std::size_t count = 0;
  std::vector<Property> properties;
};

/// Whitespace-separated tokens with their line and column; PLY's ASCII body does not
/// need to keep one element per line, so the body is read token by token.
class Tokenizer {
 public:
  Tokenizer(const std::filesystem::path& file, std::string_view text, std::size_t pos, std::size_t line)
      : file_(file), text_(text), pos_(pos), line_(line), line_start_(pos) {}

  /// The next token; throws "file ends early" with `what` when there is none.
  std::string_view next(const char* what) {
    skip_space();
    if (pos_ == text_.size()) fail(std::string("file ends early: expected ") + what);
    const std::size_t begin = pos_;
    while (pos_ < text_.size() && !is_space(text_[pos_])) ++pos_;
    return text_.substr(begin, pos_ - begin);
  }

  bool at_end() {
    skip_space();
    return pos_ == text_.size();
  }

  /// `what` names the value without an article ("vertex coordinate").
  double number(const char* what) {
    const std::string_view t = next(what);
    const char* digits = t.data() + (t.front() == '+' ? 1 : 0);
    double value = 0;
    const auto [end, ec] = std::from_chars(digits, t.data() + t.size(), value);
    if (ec != std::errc() || end != t.data() + t.size())
      fail(std::string("expected a ") + what + ", found \"" + std::string(t) + '"');
    if (!std::isfinite(value)) fail(std::string("expected a finite ") + what + ", found \"" + std::string(t) + '"');
    return value;
  }

  long long integer(const char* what) {
    const std::string_view t = next(what);
    const char* digits = t.data() + (t.front() == '+' ? 1 : 0);
    long long value = 0;
    const auto [end, ec] = std::from_chars(digits, t.data() + t.size(), value);
    if (ec != std::errc() || end != t.data() + t.size())
      fail(std::string("expected ") + what + ", found \"" + std::string(t) + '"');
    return value;
  }

  /// Error at the last token read.
  [[noreturn]] void fail(const std::string& what) const { throw LoadError(file_, token_line_, token_column_, what); }

 private:
  /// Moves past spaces and newlines to the next token and records where it starts.
  void skip_space() {
    while (pos_ < text_.size() && is_space(text_[pos_])) {
      if (text_[pos_] == '\n') {
        ++line_;
        line_start_ = pos_ + 1;
      }
      ++pos_;
    }
    token_line_ = line_;
    token_column_ = pos_ - line_start_ + 1;
  }

  const std::filesystem::path& file_;
  std::string_view text_;
  std::size_t pos_;
  std::size_t line_;
  std::size_t line_start_;
  std::size_t token_line_ = 0;
  std::size_t token_column_ = 0;
};

struct Header {
  std::vector<Element> elements;
  std::size_t body_offset = 0;
  std::size_t body_line = 0;  ///< line number of the first body line
};

Header parse_header(const std::filesystem::path& file, std::string_view text) {
  Header header;
  std::size_t pos = 0;
  bool saw_format = false;
  for (std::size_t line = 1;; ++line) {
    if (pos >= text.size()) throw LoadError(file, line, 1, "file ends in the header: expected end_header");
    std::size_t nl = text.find('\n', pos);
    if (nl == std::string_view::npos) nl = text.size();
    std::string_view content = text.substr(pos, nl - pos);
    while (!content.empty() && is_space(content.back())) content.remove_suffix(1);
    pos = nl + 1;

    // Split into words, remembering where each starts for the column.
    std::vector<std::string_view> words;
    std::vector<std::size_t> columns;
    for (std::size_t i = 0; i < content.size();) {
      while (i < content.size() && is_space(content[i])) ++i;
      if (i == content.size()) break;
      const std::size_t b = i;
      while (i < content.size() && !is_space(content[i])) ++i;
      words.push_back(content.substr(b, i - b));
      columns.push_back(b + 1);
    }
    const auto fail = [&](std::size_t word, const std::string& what) {
      throw LoadError(file, line, word < columns.size() ? columns[word] : 1, what);
    };

    if (line == 1) {
      if (words.size() != 1 || words[0] != "ply") fail(0, "expected \"ply\" on the first line (not a PLY file)");
      continue;
    }
    if (words.empty()) continue;
    const std::string_view keyword = words[0];
    if (keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "format") {
      if (words.size() != 3) fail(0, "expected \"format ascii 1.0\"");
      if (words[1] == "binary_little_endian" || words[1] == "binary_big_endian")
        fail(1, "binary PLY not supported (format " + std::string(words[1]) + "); convert the file to ASCII");
      if (words[1] != "ascii") fail(1, "expected format ascii, found \"" + std::string(words[1]) + '"');
      if (words[2] != "1.0") fail(2, "expected PLY version 1.0, found \"" + std::string(words[2]) + '"');
      saw_format = true;
    } else if (keyword == "element") {
      if (!saw_format) fail(0, "expected \"format ascii 1.0\" before the first element");
      if (words.size() != 3) fail(0, "expected \"element NAME COUNT\"");
      Element e;
      e.name = std::string(words[1]);
      const auto [end, ec] = std::from_chars(words[2].data(), words[2].data() + words[2].size(), e.count);
      if (ec != std::errc() || end != words[2].data() + words[2].size())
        fail(2, "expected an element count (a non-negative integer), found \"" + std::string(words[2]) + '"');
      header.elements.push_back(std::move(e));
    } else if (keyword == "property") {
      if (header.elements.empty()) fail(0, "property before any element");
      Property p;
      if (words.size() == 5 && words[1] == "list") {
        if (!is_scalar_type(words[2])) fail(2, "unknown PLY type \"" + std::string(words[2]) + '"');
        if (!is_scalar_type(words[3])) fail(3, "unknown PLY type \"" + std::string(words[3]) + '"');
        p.is_list = true;
        p.name = std::string(words[4]);
      } else if (words.size() == 3) {
        if (!is_scalar_type(words[1])) fail(1, "unknown PLY type \"" + std::string(words[1]) + '"');
        p.name = std::string(words[2]);
      } else {
        fail(0, "expected \"property TYPE NAME\" or \"property list COUNT_TYPE TYPE NAME\"");
      }
      header.elements.back().properties.push_back(std::move(p));
    } else if (keyword == "end_header") {
      if (!saw_format) fail(0, "expected \"format ascii 1.0\" before end_header");
      header.body_offset = std::min(pos, text.size());
      header.body_line = line + 1;
      return header;
    } else {
      fail(0, "unknown header line \"" + std::string(keyword) + "\" (expected format, element, property, comment or "
                                                                   "end_header)");
    }
  }
}

int property_index(const Element& e, std::string_view name) {
  for (std::size_t i = 0; i < e.properties.size(); ++i)
    if (e.properties[i].name == name) return static_cast<int>(i);
  return -1;
}

/// The face element's list of corners: vertex_indices, or vertex_index; -1 when absent.
int corner_list_index(const Element& e) {
  const int list = property_index(e, "vertex_indices");
  return list >= 0 ? list : property_index(e, "vertex_index");
}

/// The vertex count, after checking the properties' roles: x, y and z scalars, a face's
/// corner list. Checked before any data is read.
std::size_t checked_vertex_count(const std::filesystem::path& file, const Header& header) {
  std::size_t vertex_count = 0;
  for (const Element& e : header.elements) {
    if (e.name == "vertex") {
      vertex_count = e.count;
      for (const char* axis : {"x", "y", "z"}) {
        const int i = property_index(e, axis);
        if (i < 0 || e.properties[i].is_list)
          throw LoadError(file, std::string("the vertex element has no scalar property ") + axis);
      }
    } else if (e.name == "face" && corner_list_index(e) < 0) {
      throw LoadError(file, "the face element has no list property vertex_indices (or vertex_index)");
    }
  }
  return vertex_count;
}

/// Counts the body cannot hold fail before anything is allocated for them: each record of
/// an element with P properties is at least P one-character tokens with a separator after
/// all but the file's last.
void check_counts_fit(const std::filesystem::path& file, const Header& header, std::size_t body_bytes) {
  for (const Element& e : header.elements) {
    const std::size_t min_bytes = 2 * e.properties.size();
    if (min_bytes != 0 && e.count > (body_bytes + 1) / min_bytes)
      throw LoadError(file, "the header claims " + std::to_string(e.count) + " " + e.name + " records, but the " +
                                std::to_string(body_bytes) + " bytes after end_header hold at most " +
                                std::to_string((body_bytes + 1) / min_bytes) + " (truncated or corrupt file)");
  }
}

/// What the body's records add up to: the vertices and the faces fanned into triangles.
struct PlyBody {
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices;
};

/// One face's corner list, fanned into triangles appended to `indices`.
void read_face(Tokenizer& in, std::size_t vertex_count, std::vector<std::uint32_t>& face,
               std::vector<std::uint32_t>& indices) {
  const long long count = in.integer("a face's vertex count");
  if (count < 3) in.fail("a face needs at least 3 vertices, found " + std::to_string(count));
  if (static_cast<unsigned long long>(count) > kMaxFaceCorners)
    in.fail("a face has " + std::to_string(count) + " corners, more than " + std::to_string(kMaxFaceCorners) +
            " (the limit of one face)");
  face.clear();
  for (long long i = 0; i < count; ++i) {
    const long long index = in.integer("a vertex index");
    if (index < 0 || static_cast<unsigned long long>(index) >= vertex_count)
      in.fail("vertex index " + std::to_string(index) + " is out of range: the file has " +
              std::to_string(vertex_count) + " vertices (indices start at 0)");
    face.push_back(static_cast<std::uint32_t>(index));
  }
  for (std::size_t i = 1; i + 1 < face.size(); ++i) indices.insert(indices.end(), {face[0], face[i], face[i + 1]});
}

/// A property this loader does not use, skipped (a list with its values).
void skip_property(Tokenizer& in, const Property& prop) {
  if (!prop.is_list) {
    in.next("a property value");
    return;
  }
  const long long count = in.integer("a list length");
  if (count < 0) in.fail("expected a list length, found " + std::to_string(count));
  for (long long i = 0; i < count; ++i) in.next("a list value");
}

/// The records of one element: a vertex's coordinates, a face's corners, the rest skipped.
void read_element(Tokenizer& in, const Element& e, std::size_t vertex_count, PlyBody& body) {
  const bool is_vertex = e.name == "vertex";
  const int x = is_vertex ? property_index(e, "x") : -1;
  const int y = is_vertex ? property_index(e, "y") : -1;
  const int z = is_vertex ? property_index(e, "z") : -1;
  const int list = e.name == "face" ? corner_list_index(e) : -1;
  std::vector<std::uint32_t> face;
  // An element without properties has no data, whatever its count.
  for (std::size_t n = 0; n < e.count && !e.properties.empty(); ++n) {
    glm::vec3 p{0.0f};
    for (int k = 0; k < static_cast<int>(e.properties.size()); ++k) {
      if (k == x || k == y || k == z) {
        const double v = in.number("vertex coordinate");
        if (std::fabs(v) > 3.4028234663852886e38) in.fail("vertex coordinate out of float range");
        p[k == x ? 0 : k == y ? 1 : 2] = static_cast<float>(v);
      } else if (k == list) {
        read_face(in, vertex_count, face, body.indices);
      } else {
        skip_property(in, e.properties[k]);
      }
    }
    if (is_vertex) body.positions.push_back(p);
  }
}

/// The body's triangles appended to the scene's mesh with one material.
void commit(const PlyBody& body, std::uint32_t material, MeshDesc& mesh) {
  const std::size_t base = mesh.positions.size();
  const bool mesh_has_normals = !mesh.corner_normals.empty();
  mesh.positions.insert(mesh.positions.end(), body.positions.begin(), body.positions.end());
  mesh.indices.reserve(mesh.indices.size() + body.indices.size());
  for (const std::uint32_t i : body.indices) mesh.indices.push_back(static_cast<std::uint32_t>(base + i));
  mesh.material.insert(mesh.material.end(), body.indices.size() / 3, material);
  if (mesh_has_normals) complete_corner_normals(mesh);
}

}  // namespace

void load_ply(const std::filesystem::path& file, const glm::mat4& transform,
              std::optional<std::uint32_t> material_override, SceneDesc& into) {
  if (material_override && *material_override >= into.materials.size())
    throw std::invalid_argument("load_ply: material_override " + std::to_string(*material_override) +
                                " is not an index into the scene's " + std::to_string(into.materials.size()) +
                                " materials");
  const std::string text = read_text_file(file);
  const Header header = parse_header(file, text);
  const std::size_t vertex_count = checked_vertex_count(file, header);
  check_counts_fit(file, header, text.size() - header.body_offset);
  if (vertex_count >= 0xffffffffu)
    throw LoadError(file, "the header claims " + std::to_string(vertex_count) + " vertices; the limit is 2^32 - 2");

  PlyBody body;
  body.positions.reserve(vertex_count);
  Tokenizer in(file, text, header.body_offset, header.body_line);
  for (const Element& e : header.elements) read_element(in, e, vertex_count, body);
  if (!in.at_end()) in.fail("unexpected data after the last element");

  if (into.mesh.positions.size() + body.positions.size() >= 0xffffffffu)
    throw LoadError(file, "too many vertices in the scene (more than 2^32 - 1)");
  transform_positions(file, transform, body.positions, 0);
  commit(body, material_override ? *material_override : ensure_default_material(into.materials), into.mesh);
}

}  // namespace volley::io
