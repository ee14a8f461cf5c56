#include "accel/accel_impl.h"

#include <cstdlib>

#include "core/bvh_traverse.h"

namespace volley {
namespace {

core::BBox triangle_box(const glm::vec3* p) {
  core::BBox b;
  for (int k = 0; k < 3; ++k) b.extend(p[k]);
  return b;
}

core::RayT<float> to_core(const Ray& r) {
  return {{r.org[0], r.org[1], r.org[2]}, r.tmin, {r.dir[0], r.dir[1], r.dir[2]}, r.tmax};
}

}  // namespace

void Accel::Impl::build() {
  const std::size_t n = triangle_ids.size();
  std::vector<core::BBox> boxes(n);
  degenerate = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const glm::vec3* p = &triangles[3 * i];
    // Degenerate triangles can never be hit: an empty box keeps them out of traversal.
    if (core::is_degenerate(p[0], p[1], p[2])) {
      ++degenerate;
      continue;
    }
    boxes[i] = triangle_box(p);
  }
  build_options = core::BvhBuildOptions{};
  if (isa != Isa::scalar) {
    // A leaf costs one block test per W triangles: allow leaves up to a full block and
    // price a triangle at a fraction of a node visit so the SAH fills the lanes.
    const int w = isa == Isa::avx512 ? 16 : isa == Isa::avx2 ? 8 : 4;
    build_options.max_leaf_size = w;
    build_options.intersection_cost = std::getenv("VOLLEY_LEAF_COST") ? std::atof(std::getenv("VOLLEY_LEAF_COST")) : 1.0f;
  }
  triangle_bvh = n ? core::build_bvh(boxes, build_options) : core::Bvh{};

  plane_triangles.clear();
  kernels.reset();
  node_blocks.clear();
  if (isa != Isa::scalar && n) {
    build_blocks();
  } else if (test == TriangleTest::plane) {
    plane_triangles.reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
      const glm::vec3* p = &triangles[3 * i];
      plane_triangles.push_back(core::PlaneTriangle<float>::from(p[0], p[1], p[2]));
    }
  }

  std::vector<core::BBox> poly_boxes;
  for (const auto& poly : polygons) {
    core::BBox b;
    for (const auto& v : poly.vertices) b.extend(v);
    poly_boxes.push_back(b);
  }
  polygon_bvh = polygons.empty() ? core::Bvh{} : core::build_bvh(poly_boxes, build_options);
}

// Packs each BVH leaf's triangles into its own run of SIMD blocks.
void Accel::Impl::build_blocks() {
  kernels = simd::TriangleKernels::create(test, isa);
  std::vector<float> xyz;
  std::vector<std::uint32_t> ids, groups, leaves;
  xyz.reserve(triangles.size() * 3);
  ids.reserve(triangle_ids.size());
  for (std::uint32_t node = 0; node < triangle_bvh.nodes.size(); ++node) {
    const core::BvhNode& leaf = triangle_bvh.nodes[node];
    if (!leaf.is_leaf()) continue;
    leaves.push_back(node);
    groups.push_back(std::uint32_t(ids.size()));
    for (std::uint32_t i = leaf.first_or_child; i < leaf.first_or_child + leaf.count; ++i) {
      const std::uint32_t prim = triangle_bvh.prim_index[i];
      for (int k = 0; k < 3; ++k)
        xyz.insert(xyz.end(), {triangles[3 * prim + k].x, triangles[3 * prim + k].y, triangles[3 * prim + k].z});
      ids.push_back(triangle_ids[prim]);
    }
  }
  groups.push_back(std::uint32_t(ids.size()));
  const auto ranges = kernels->build(xyz.data(), ids.data(), ids.size(), groups.data(), leaves.size());
  node_blocks.assign(triangle_bvh.nodes.size(), simd::BlockRange{0, 0});
  for (std::size_t g = 0; g < leaves.size(); ++g) node_blocks[leaves[g]] = ranges[g];
}

template <bool AnyHit>
bool Accel::Impl::trace_triangles_simd(const Ray& ray, Hit& hit) const {
  const simd::PreparedRay prepared = kernels->prepare(ray);
  return core::traverse_leaves<AnyHit>(triangle_bvh, to_core(ray), [&](std::uint32_t node, float& tmax) {
    if constexpr (AnyHit) {
      return kernels->occluded(prepared, node_blocks[node]);
    } else {
      const float before = hit.t;
      kernels->intersect(prepared, node_blocks[node], hit);
      if (!(hit.t < before)) return false;
      tmax = hit.t;
      return true;
    }
  });
}

template <bool AnyHit>
bool Accel::Impl::trace_triangles_scalar(const core::RayT<float>& r, Hit& hit) const {
  const core::WoopRay<float> woop = core::make_woop_ray(r.dir);
  return core::traverse<AnyHit>(triangle_bvh, r, [&](std::uint32_t prim, float& tmax) {
    const glm::vec3* p = &triangles[3 * prim];
    core::RayT<float> q = r;
    q.tmax = tmax;
    core::TriHit<float> h;
    bool ok = false;
    switch (test) {
      case TriangleTest::plane:
        ok = core::intersect_plane(q, plane_triangles[prim], h);
        break;
      case TriangleTest::moller:
        ok = core::intersect_moller(q, p[0], p[1], p[2], h);
        break;
      case TriangleTest::watertight:
        ok = core::intersect_watertight(q, woop, p[0], p[1], p[2], h);
        break;
    }
    if (!ok) return false;
    tmax = h.t;
    hit = {h.t, h.u, h.v, triangle_ids[prim]};
    return true;
  });
}

template <bool AnyHit>
bool Accel::Impl::trace(const Ray& ray, Hit& hit) const {
  core::RayT<float> r = to_core(ray);
  bool found = false;
  if (!triangle_bvh.nodes.empty()) {
    found = kernels ? trace_triangles_simd<AnyHit>(ray, hit) : trace_triangles_scalar<AnyHit>(r, hit);
    if (AnyHit && found) return true;
    r.tmax = found ? hit.t : r.tmax;
  }
  if (!polygon_bvh.nodes.empty()) {
    found |= core::traverse<AnyHit>(polygon_bvh, r, [&](std::uint32_t prim, float& tmax) {
      core::RayT<float> q = r;
      q.tmax = tmax;
      float t;
      if (!core::intersect_polygon(q, polygons[prim], t)) return false;
      tmax = t;
      hit = {t, 0.0f, 0.0f, polygon_ids[prim]};
      return true;
    });
  }
  return found;
}

Hit Accel::Impl::intersect(const Ray& ray) const {
  Hit hit;
  trace<false>(ray, hit);
  return hit;
}

bool Accel::Impl::occluded(const Ray& ray) const {
  Hit hit;
  return trace<true>(ray, hit);
}

AccelInfo Accel::Impl::info() const {
  AccelInfo info;
  info.triangles = triangle_ids.size();
  info.degenerate = degenerate;
  info.polygons = polygons.size();
  info.test = test;
  info.isa = isa;
  info.build_seconds = build_seconds;
  for (const core::Bvh* bvh : {&triangle_bvh, &polygon_bvh}) {
    if (bvh->nodes.empty()) continue;
    const core::BvhStats s = core::bvh_stats(*bvh, build_options);
    info.nodes += s.nodes;
    info.leaves += s.leaves;
    info.depth = std::max(info.depth, s.depth);
    info.bytes += s.bytes;
    if (bvh == &triangle_bvh) {
      info.sah_cost = s.sah_cost;
      info.mean_leaf_size = s.mean_leaf_size;
    }
  }
  // The triangle layout of the test in use (the input copy kept for re-commits not counted).
  if (kernels)
    info.bytes += kernels->bytes();
  else if (test == TriangleTest::plane)
    info.bytes += plane_triangles.size() * sizeof(core::PlaneTriangle<float>);
  else
    info.bytes += triangles.size() * sizeof(glm::vec3);
  return info;
}

}  // namespace volley
