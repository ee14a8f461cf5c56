// Names of triangle tests, ISAs and build qualities, shared by the CLI, VOLLEY_ISA and reports.
#include "volley/options.h"

namespace volley {
namespace {

// One table per enum: its to_string and its parse read the same names.
template <class E>
struct Name {
  E value;
  std::string_view name;
};

constexpr Name<TriangleTest> kTriangleTests[] = {
    {TriangleTest::plane, "plane"}, {TriangleTest::moller, "moller"}, {TriangleTest::watertight, "watertight"}};
constexpr Name<Isa> kIsas[] = {{Isa::automatic, "auto"},
                               {Isa::scalar, "scalar"},
                               {Isa::sse42, "sse4.2"},
                               {Isa::avx2, "avx2"},
                               {Isa::avx512, "avx512"}};
constexpr Name<BuildQuality> kBuildQualities[] = {{BuildQuality::medium, "medium"}, {BuildQuality::high, "high"}};

template <class E, std::size_t N>
std::string_view name_of(E value, const Name<E> (&names)[N]) {
  for (const Name<E>& n : names)
    if (n.value == value) return n.name;
  return "?";
}

template <class E, std::size_t N>
std::optional<E> value_of(std::string_view name, const Name<E> (&names)[N]) {
  for (const Name<E>& n : names)
    if (n.name == name) return n.value;
  return std::nullopt;
}

}  // namespace

std::string_view to_string(TriangleTest test) { return name_of(test, kTriangleTests); }
std::string_view to_string(Isa isa) { return name_of(isa, kIsas); }
std::string_view to_string(BuildQuality quality) { return name_of(quality, kBuildQualities); }

std::optional<BuildQuality> parse_build_quality(std::string_view name) { return value_of(name, kBuildQualities); }
std::optional<TriangleTest> parse_triangle_test(std::string_view name) { return value_of(name, kTriangleTests); }

std::optional<Isa> parse_isa(std::string_view name) {
  if (name == "sse42") return Isa::sse42;
  return value_of(name, kIsas);
}

}  // namespace volley
