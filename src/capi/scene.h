// The object behind the C API's opaque volley_scene handle.
#pragma once
#include <cstdint>

#include "volley/accel.h"
#include "volley/volley.h"

/// A volley::Accel plus the state the C API checks before calling it (global namespace:
/// volley.h declares `struct volley_scene`).
struct volley_scene {
  volley::Accel accel;
  std::uint64_t prims = 0;  ///< triangles + polygons added (prim ids handed out)
  bool committed = false;   ///< committed since the last addition
};

namespace volley::capi {

/// The failure of require_committed (out of line: the check itself is on every query).
[[noreturn]] void fail_not_committed(const volley_scene* scene);

/// Fails with VOLLEY_ERROR_INVALID_ARGUMENT for a NULL scene and with
/// VOLLEY_ERROR_NOT_COMMITTED for one not committed since its last change.
inline void require_committed(const volley_scene* scene) {
  if (scene == nullptr || !scene->committed) fail_not_committed(scene);
}

}  // namespace volley::capi
