// Names of triangle tests, ISAs and build qualities, shared by the CLI, VOLLEY_ISA and reports.
#include "volley/options.h"

namespace volley {

std::string_view to_string(TriangleTest test) {
  switch (test) {
    case TriangleTest::plane: return "plane";
    case TriangleTest::moller: return "moller";
    case TriangleTest::watertight: return "watertight";
  }
  return "?";
}

std::string_view to_string(Isa isa) {
  switch (isa) {
    case Isa::automatic: return "auto";
    case Isa::scalar: return "scalar";
    case Isa::sse42: return "sse4.2";
    case Isa::avx2: return "avx2";
    case Isa::avx512: return "avx512";
  }
  return "?";
}

std::string_view to_string(BuildQuality quality) {
  switch (quality) {
    case BuildQuality::medium: return "medium";
    case BuildQuality::high: return "high";
  }
  return "?";
}

std::optional<BuildQuality> parse_build_quality(std::string_view name) {
  for (BuildQuality q : {BuildQuality::medium, BuildQuality::high})
    if (name == to_string(q)) return q;
  return std::nullopt;
}

std::optional<TriangleTest> parse_triangle_test(std::string_view name) {
  for (TriangleTest t : {TriangleTest::plane, TriangleTest::moller, TriangleTest::watertight})
    if (name == to_string(t)) return t;
  return std::nullopt;
}

std::optional<Isa> parse_isa(std::string_view name) {
  for (Isa isa : {Isa::automatic, Isa::scalar, Isa::sse42, Isa::avx2, Isa::avx512})
    if (name == to_string(isa)) return isa;
  if (name == "sse42") return Isa::sse42;
  return std::nullopt;
}

}  // namespace volley
