// Closed indexed meshes with float-exact vertices for leak measurements (docs/accuracy.md stress
// items 1, 2, 8), their exact targets (shared vertices, edge midpoints, quad diagonals) and
// interior origins.
#pragma once
#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "accuracy/mesh.h"

namespace volley::accuracy {

/// A closed mesh, points on its surface to aim at (in mesh coordinates, exact in double),
/// and a predicate "strictly inside with margin" for origins.
struct ClosedMesh {
  std::string name;
  Mesh mesh;
  std::vector<std::array<double, 3>> targets;  ///< exact points on the surface (before any offset)
  std::vector<std::array<double, 3>> origins;  ///< interior points (before any offset)
  /// Distance of p (mesh coordinates, double) from the surface, positive inside; a lower bound.
  double (*depth)(const std::array<double, 3>& p, double size) = nullptr;
  double size = 0;
};

/// The surface of the cube [0, n]^3 as unit quads on integer coordinates, each quad split on
/// an alternating diagonal; shared vertices. Targets: every half-integer point of the faces
/// (vertices, edge midpoints, diagonal midpoints = quad centres).
ClosedMesh grid_cube(int n);

/// An icosphere (icosahedron subdivided `levels` times) of radius `radius`, vertices rounded
/// to integers (so edge midpoints are half-integers, exact). Targets: vertices and edge
/// midpoints. Centred at (radius, radius, radius) so that coordinates are non-negative.
ClosedMesh icosphere(int levels, double radius);

/// Generalized winding number of a closed triangle mesh at p, in double (Van Oosterom and
/// Strackee's solid angles): 1 inside a consistently oriented closed mesh, 0 outside,
/// near those away from the surface. The inside/outside reference of the query checks.
double winding_number(const Mesh& m, const std::array<double, 3>& p);

/// Rays of a closed mesh moved by `offset` (every coordinate + offset, rounded to float):
/// from every interior origin that is still strictly inside after rounding (depth > 0)
/// to every target, t = 1 at the (rounded) target. `exact_targets` counts targets whose
/// moved position is still exactly representable (the rays then pass exactly through the
/// shared vertex or edge point: the directions are differences of nearby floats, exact).
/// `repeat` > 1 adds random interior origins up to repeat times the mesh's own.
std::vector<Ray> closed_mesh_rays(const ClosedMesh& c, float offset, std::size_t& exact_targets,
                                  std::size_t& origins_used, std::size_t repeat = 1);

}  // namespace volley::accuracy
