// volley public API: build and query options.
#pragma once
#include <optional>
#include <string>
#include <string_view>

#include "volley/export.h"

namespace volley {

/// Ray/triangle test used by an Accel. Each builds its own triangle layout.
enum class TriangleTest {
  plane,       ///< the notes' algorithm 1: ray/plane, then half-plane (edge plane) tests
  moller,      ///< algorithm 2: the 3x3 barycentric system by Cramer's rule (Moller-Trumbore)
  watertight,  ///< Woop-Benthin-Wald 2013: no cracks at shared edges and vertices
};

/// Instruction set for the kernels. `automatic` picks the best the CPU supports
/// (overridden by the VOLLEY_ISA environment variable); `scalar` runs the oracle.
enum class Isa {
  automatic,  ///< the widest the CPU supports, unless VOLLEY_ISA names one
  scalar,     ///< the scalar oracle (binary BVH, one triangle at a time)
  sse42,      ///< SSE4.2: 4 lanes
  avx2,       ///< AVX2 + FMA: 8 lanes
  avx512,     ///< AVX-512 (F, DQ, BW, VL): 16 lanes
};

/// Options fixed at Accel::commit.
struct Options {
  TriangleTest test = TriangleTest::watertight;  ///< ray/triangle test (and triangle layout)
  Isa isa = Isa::automatic;                      ///< kernel ISA; commit throws Error if the CPU lacks it
};

/// Names as used on the command line ("plane", "moller", "watertight").
VOLLEY_API std::string_view to_string(TriangleTest test);
/// Names as used on the command line ("auto", "scalar", "sse4.2", "avx2", "avx512").
VOLLEY_API std::string_view to_string(Isa isa);
/// Parses a command-line name; std::nullopt for an unknown name.
VOLLEY_API std::optional<TriangleTest> parse_triangle_test(std::string_view name);
/// Parses a command-line name; std::nullopt for an unknown name.
VOLLEY_API std::optional<Isa> parse_isa(std::string_view name);

}  // namespace volley
