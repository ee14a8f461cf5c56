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

/// How much work commit puts into the BVH (Embree's build qualities).
enum class BuildQuality {
  medium,  ///< binned SAH over the triangles' boxes: fast to build, the default
  high,    ///< also spatial splits (SBVH): a triangle may be cut into several leaves' references;
           ///< several times slower to build, fewer nodes per ray where triangles are long and
           ///< overlap (perf/reports/rays.md has the scenes where it pays and where it does not)
};

/// Options fixed at Accel::commit.
struct Options {
  TriangleTest test = TriangleTest::watertight;  ///< ray/triangle test (and triangle layout)
  Isa isa = Isa::automatic;                      ///< kernel ISA; commit throws Error if the CPU lacks it
  /// Conservative BVH traversal: box exit distances padded against rounding (Ize 2013)
  /// and NaN-safe slab operand order, so that `watertight` stays watertight through the
  /// whole BVH, not only per triangle. false = the plain slab test (faster, may leak
  /// at box boundaries).
  bool robust = true;
  /// Isa::scalar only: run the oracle's triangle test in double precision (vertices and
  /// rays widened from float, t rounded back). The reference of the accuracy report;
  /// commit throws Error with a SIMD ISA.
  bool reference_double = false;
  /// After update_vertices(), with nothing else changed since the last commit (no geometry
  /// added, enabled or disabled; the same options), commit refits the existing BVH: the same
  /// tree, boxes and triangle data recomputed, about 10x faster than a build. It builds
  /// instead when a triangle that the last build left out for having no area has gained
  /// some (a build puts all triangles of a moved geometry into the tree, so this happens at
  /// most once per geometry), or when the refit leaves the SAH cost more than
  /// kRefitRebuildGrowth times that of the last build. false: always build.
  bool refit = true;
  /// BVH build quality. high applies to every ISA; answers are medium's (a triangle reached
  /// through several references is reported once) but where float rounding decides: a tie
  /// between two triangles at one t, or a hit at t near 0 on the ray's own start triangle,
  /// may come out the other way (a few rays in 100,000 of the diffuse workloads; perf/reports/rays.md).
  BuildQuality quality = BuildQuality::medium;
};

/// SAH cost growth (after a refit, against the last full build) past which commit
/// rebuilds instead (Options::refit).
inline constexpr double kRefitRebuildGrowth = 1.5;

/// Names as used on the command line ("plane", "moller", "watertight").
VOLLEY_API std::string_view to_string(TriangleTest test);
/// Names as used on the command line ("auto", "scalar", "sse4.2", "avx2", "avx512").
VOLLEY_API std::string_view to_string(Isa isa);
/// Parses a command-line name; std::nullopt for an unknown name.
VOLLEY_API std::optional<TriangleTest> parse_triangle_test(std::string_view name);
/// Parses a command-line name; std::nullopt for an unknown name.
VOLLEY_API std::optional<Isa> parse_isa(std::string_view name);
/// Names as used on the command line ("medium", "high").
VOLLEY_API std::string_view to_string(BuildQuality quality);
/// Parses a command-line name; std::nullopt for an unknown name.
VOLLEY_API std::optional<BuildQuality> parse_build_quality(std::string_view name);

}  // namespace volley
