#include "io/json_values.h"

#include <cmath>
#include <vector>

#include "io/load_error.h"
#include "io/text_file.h"

namespace volley::io {
namespace {

/// Tracks the JSON path while nlohmann parses, to report duplicate keys (which the
/// DOM parser would silently collapse to the last one).
class DuplicateKeyCheck {
 public:
  explicit DuplicateKeyCheck(const std::filesystem::path& file) : file_(file) {}

  bool operator()(int /*depth*/, Json::parse_event_t event, Json& parsed) {
    using E = Json::parse_event_t;
    switch (event) {
      case E::object_start:
      case E::array_start:
        stack_.push_back({event == E::object_start, {}, {}, 0});
        break;
      case E::key: {
        Frame& top = stack_.back();
        const std::string& key = parsed.get_ref<const std::string&>();
        for (const std::string& k : top.keys)
          if (k == key) path_of_top().fail("duplicate key \"" + key + "\"");
        top.keys.push_back(key);
        top.last_key = key;
        break;
      }
      case E::object_end:
      case E::array_end:
        stack_.pop_back();
        value_done();
        break;
      case E::value:
        value_done();
        break;
    }
    return true;
  }

 private:
  struct Frame {
    bool object;
    std::vector<std::string> keys;
    std::string last_key;
    std::size_t index;  // elements completed so far (arrays)
  };

  void value_done() {
    if (!stack_.empty() && !stack_.back().object) ++stack_.back().index;
  }

  JsonPath path_of_top() const {
    JsonPath path(file_, "(top level)");
    for (std::size_t i = 0; i + 1 < stack_.size(); ++i)
      path = stack_[i].object ? path[stack_[i].last_key] : path[stack_[i].index];
    return path;
  }

  const std::filesystem::path& file_;
  std::vector<Frame> stack_;
};

}  // namespace

Json parse_json(const std::filesystem::path& file, const std::string& text) {
  try {
    return Json::parse(text, DuplicateKeyCheck(file), /*allow_exceptions=*/true, /*ignore_comments=*/false);
  } catch (const Json::parse_error& e) {
    // e.byte is the 1-based index of the last character read (size + 1 at the end).
    const std::size_t offset = e.byte > 0 ? e.byte - 1 : 0;
    const TextPosition pos = position_of(text, offset);
    // Keep nlohmann's explanation, drop its "[json.exception...] parse error at ...: " prefix.
    std::string detail = e.what();
    const std::size_t colon = detail.find(": ", detail.find("parse error"));
    if (colon != std::string::npos) detail = detail.substr(colon + 2);
    if (offset < text.size() && text[offset] == '/')
      detail += " (comments are not allowed in scene files)";
    throw LoadError(file, pos.line, pos.column, "invalid JSON: " + detail);
  } catch (const Json::out_of_range& e) {
    // "number overflow parsing '1e400'" carries no position: find the number's first
    // occurrence (an earlier one would have failed first).
    const std::string what = e.what();
    const std::size_t open = what.find('\'');
    const std::size_t close = what.rfind('\'');
    if (open != std::string::npos && close > open + 1) {
      const std::size_t at = text.find(what.substr(open + 1, close - open - 1));
      if (at != std::string::npos) {
        const TextPosition pos = position_of(text, at);
        throw LoadError(file, pos.line, pos.column,
                        "invalid JSON: number " + what.substr(open + 1, close - open - 1) + " is too large");
      }
    }
    throw LoadError(file, "invalid JSON: " + what);
  }
}

JsonPath JsonPath::operator[](std::string_view key) const {
  if (path_ == "(top level)") return JsonPath(*file_, std::string(key));
  return JsonPath(*file_, path_ + "." + std::string(key));
}

JsonPath JsonPath::operator[](std::size_t index) const {
  return JsonPath(*file_, (path_ == "(top level)" ? std::string() : path_) + "[" + std::to_string(index) + "]");
}

void JsonPath::fail(const std::string& what) const { throw LoadError(*file_, path_ + ": " + what); }

std::string describe(const Json& j) {
  if (j.is_object()) return "an object";
  if (j.is_array()) return "an array of " + std::to_string(j.size());
  std::string s = j.dump();
  constexpr std::size_t kMax = 40;
  if (s.size() > kMax) s = s.substr(0, kMax) + "...";
  return s;
}

void check_object(const Json& j, const JsonPath& at, std::initializer_list<std::string_view> allowed) {
  if (!j.is_object()) at.fail(std::string("expected an object, found ") + describe(j));
  for (const auto& [key, value] : j.items()) {
    bool known = false;
    for (const std::string_view a : allowed) known |= key == a;
    if (known) continue;
    std::string list;
    for (const std::string_view a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
    at.fail("unknown key \"" + key + "\" (allowed keys: " + list + ")");
  }
}

void check_array(const Json& j, const JsonPath& at, std::size_t min_size) {
  if (!j.is_array()) at.fail(std::string("expected an array, found ") + describe(j));
  if (j.size() < min_size)
    at.fail("expected an array of at least " + std::to_string(min_size) + " elements, found " +
            std::to_string(j.size()));
}

float get_float(const Json& j, const JsonPath& at, float lo, float hi) {
  if (!j.is_number()) at.fail("expected a number, found " + describe(j));
  const double d = j.get<double>();
  if (!std::isfinite(d) || std::fabs(d) > 3.4028234663852886e38)
    at.fail("expected a finite number within float range, found " + describe(j));
  if (d < lo || d > hi) {
    auto text = [](float x) {
      std::string s = std::to_string(x);
      while (s.back() == '0') s.pop_back();
      if (s.back() == '.') s.pop_back();
      return s;
    };
    at.fail("expected a number from " + text(lo) + " to " + text(hi) + ", found " + describe(j));
  }
  return static_cast<float>(d);
}

std::int64_t get_int(const Json& j, const JsonPath& at, std::int64_t lo, std::int64_t hi) {
  const std::string range = "expected an integer from " + std::to_string(lo) + " to " + std::to_string(hi);
  std::int64_t v = 0;
  if (j.is_number_unsigned()) {
    if (j.get<std::uint64_t>() > static_cast<std::uint64_t>(hi)) at.fail(range + ", found " + describe(j));
    v = static_cast<std::int64_t>(j.get<std::uint64_t>());
  } else if (j.is_number_integer()) {
    v = j.get<std::int64_t>();
  } else if (j.is_number_float()) {
    const double d = j.get<double>();
    if (!(d == std::floor(d)) || d < static_cast<double>(lo) || d > static_cast<double>(hi))
      at.fail(range + ", found " + describe(j));
    v = static_cast<std::int64_t>(d);
  } else {
    at.fail(range + ", found " + describe(j));
  }
  if (v < lo || v > hi) at.fail(range + ", found " + describe(j));
  return v;
}

std::uint64_t get_uint64(const Json& j, const JsonPath& at) {
  if (j.is_number_unsigned()) return j.get<std::uint64_t>();
  if (j.is_number_integer() && j.get<std::int64_t>() >= 0) return static_cast<std::uint64_t>(j.get<std::int64_t>());
  if (j.is_number_float()) {
    const double d = j.get<double>();
    if (d >= 0 && d == std::floor(d) && d < 18446744073709551616.0) return static_cast<std::uint64_t>(d);
  }
  at.fail("expected a non-negative integer, found " + describe(j));
}

glm::vec3 get_vec3(const Json& j, const JsonPath& at) {
  if (!j.is_array() || j.size() != 3) at.fail("expected an array of 3 numbers, found " + describe(j));
  return {get_float(j[0], at[0]), get_float(j[1], at[1]), get_float(j[2], at[2])};
}

glm::vec3 get_colour(const Json& j, const JsonPath& at, float max) {
  const bool bounded = max < 3.4e38f;
  const std::string expected = bounded ? "expected a colour (a number or [r, g, b]) with channels from 0 to " +
                                             std::to_string(static_cast<int>(max))
                                       : "expected a colour (a number or [r, g, b]) with channels of 0 or more";
  glm::vec3 c;
  if (j.is_number()) {
    c = glm::vec3(get_float(j, at));
  } else if (j.is_array() && j.size() == 3 && j[0].is_number() && j[1].is_number() && j[2].is_number()) {
    c = get_vec3(j, at);
  } else {
    at.fail(expected + ", found " + describe(j));
  }
  if (!(c.x >= 0 && c.y >= 0 && c.z >= 0 && c.x <= max && c.y <= max && c.z <= max))
    at.fail(expected + ", found " + j.dump());
  return c;
}

const std::string& get_string(const Json& j, const JsonPath& at) {
  if (!j.is_string()) at.fail(std::string("expected a string, found ") + describe(j));
  return j.get_ref<const std::string&>();
}

}  // namespace volley::io
