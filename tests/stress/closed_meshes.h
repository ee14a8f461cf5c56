// Closed meshes of the leak tests (stress items 1, 2, 8): the generators live in
// src/apps/accuracy/closed_meshes.h, shared with `volley accuracy`.
#pragma once
#include "accuracy/closed_meshes.h"
#include "stress_util.h"

namespace stress {

using volley::accuracy::closed_mesh_rays;
using volley::accuracy::ClosedMesh;
using volley::accuracy::grid_cube;
using volley::accuracy::icosphere;

}  // namespace stress
