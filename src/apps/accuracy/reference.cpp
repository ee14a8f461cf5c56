#include "accuracy/reference.h"

namespace volley::accuracy {

RefHit reference(const Ray& r, const std::array<double, 3>& p0, const std::array<double, 3>& p1,
                 const std::array<double, 3>& p2) {
  using V = std::array<double, 3>;
  const auto sub = [](const V& a, const V& b) { return V{a[0] - b[0], a[1] - b[1], a[2] - b[2]}; };
  const auto cross = [](const V& a, const V& b) {
    return V{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  };
  const auto dot = [](const V& a, const V& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
  const V o{r.org[0], r.org[1], r.org[2]}, d{r.dir[0], r.dir[1], r.dir[2]};
  const V e1 = sub(p1, p0), e2 = sub(p2, p0);
  const V p = cross(d, e2);
  const double det = dot(e1, p);
  RefHit h;
  if (det == 0.0) return h;
  const V s = sub(o, p0);
  const V q = cross(s, e1);
  h.ok = true;
  h.u = dot(s, p) / det;
  h.v = dot(d, q) / det;
  h.t = dot(e2, q) / det;
  return h;
}

}  // namespace volley::accuracy
