// volley public API: build and query options.
#pragma once
#include <optional>
#include <string>
#include <string_view>

namespace volley {

/// Ray/triangle test used by an Accel. Each builds its own triangle layout.
enum class TriangleTest {
  plane,       ///< the notes' algorithm 1: ray/plane, then half-plane (edge plane) tests
  moller,      ///< algorithm 2: the 3x3 barycentric system by Cramer's rule (Moller-Trumbore)
  watertight,  ///< Woop-Benthin-Wald 2013: no cracks at shared edges and vertices
};

/// Instruction set for the kernels. `automatic` picks the best the CPU supports
/// (overridden by the VOLLEY_ISA environment variable); `scalar` runs the oracle.
enum class Isa { automatic, scalar, sse42, avx2, avx512 };

/// Options fixed at Accel::commit.
struct Options {
  TriangleTest test = TriangleTest::watertight;
  Isa isa = Isa::automatic;
};

/// Names as used on the command line ("plane", "moller", "watertight").
std::string_view to_string(TriangleTest test);
/// Names as used on the command line ("auto", "scalar", "sse4.2", "avx2", "avx512").
std::string_view to_string(Isa isa);
/// Parses a command-line name; std::nullopt for an unknown name.
std::optional<TriangleTest> parse_triangle_test(std::string_view name);
/// Parses a command-line name; std::nullopt for an unknown name.
std::optional<Isa> parse_isa(std::string_view name);

}  // namespace volley
