// Rays that must never hit, made from one that does: the shared start of the "bad rays"
// cases of the scalar triangle and polygon tests.
#pragma once
#include <limits>
#include <vector>

#include "core/geometry.h"

namespace volley::test {

/// `good` with NaN, +Inf or -Inf in one origin or direction component, every component.
template <class T>
std::vector<core::RayT<T>> non_finite_variants(const core::RayT<T>& good) {
  std::vector<core::RayT<T>> bad;
  const T nan = std::numeric_limits<T>::quiet_NaN(), inf = std::numeric_limits<T>::infinity();
  for (T x : {nan, inf, -inf})
    for (int c = 0; c < 3; ++c) {
      core::RayT<T> r = good;
      r.org[c] = x;
      bad.push_back(r);
      r = good;
      r.dir[c] = x;
      bad.push_back(r);
    }
  return bad;
}

}  // namespace volley::test
