// WideAccel: the type-erased facade (baseline code). Each implementation forwards to the
// traversal kernels instantiated in the per-ISA files (extern templates in
// simd/wide/wide_traverse.h), so nothing here is compiled with wider instructions.
#include "accel/wide/wide_accel.h"

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "accel/wide/wide_build.h"
#include "simd/aligned.h"
#include "simd/isa/dispatch.h"
#include "simd/wide/wide_traverse.h"

namespace volley::accel {
namespace {

template <class Arch, TriangleTest Test, bool Robust>
class WideAccelFor final : public WideAccel {
 public:
  using Kernels = simd::WideKernels<Arch, Test, Robust>;
  using Block = typename Kernels::Block;
  static constexpr int W = Kernels::W;
  /// Whether any-hit double packets are walked as one: on AVX2, whose any-hit walk tests
  /// nodes lane by lane (a node's and a leaf call's fixed work paid once for 32 rays).
  static constexpr bool kDouble = std::is_same_v<Arch, simd::Avx2>;

  WideAccelFor()
      : WideAccel({&Kernels::intersect_erased, &Kernels::occluded_erased, &Kernels::intersect_excluding_erased,
                   &Kernels::occluded_excluding_erased, &view_}) {}
  WideAccelFor(const WideAccelFor&) = delete;  // single_ points at view_
  WideAccelFor& operator=(const WideAccelFor&) = delete;

  int block_width() const override { return W; }

  void build(const core::Bvh& bvh, const float* xyz, const std::uint32_t* ids) override {
    stats_ = build_wide<Test, W>(bvh, xyz, ids, nodes_, blocks_, root_);
    adopted_ = {};
    set_view(nodes_.data(), nodes_.size(), blocks_.data(), blocks_.size());
  }
  void refit(const float* xyz, const std::uint32_t* index_of) override {
    if (adopted_.owner) {
      // The structure lies in a read-only mapped file: refit a copy of it.
      const auto* nodes = static_cast<const simd::WideNode<simd::kWideN>*>(adopted_.nodes);
      const auto* blocks = static_cast<const Block*>(adopted_.blocks);
      nodes_.assign(nodes, nodes + adopted_.node_count);
      blocks_.assign(blocks, blocks + adopted_.block_count);
      adopted_ = {};
      set_view(nodes_.data(), nodes_.size(), blocks_.data(), blocks_.size());
    }
    stats_ = refit_wide<Test, W>(xyz, index_of, nodes_, blocks_, stats_);
  }
  void defer_handoffs(bool on) override { view_.defer_handoffs = on; }
  WideImage image() const override {
    const std::size_t node_count = adopted_.owner ? adopted_.node_count : nodes_.size();
    const std::size_t block_count = adopted_.owner ? adopted_.block_count : blocks_.size();
    return {view_.nodes, node_count, view_.blocks, block_count, sizeof(Block), root_, stats_, adopted_.owner};
  }
  std::size_t block_bytes() const override { return sizeof(Block); }
  std::size_t prim_offset() const override { return offsetof(Block, prim); }
  void adopt(WideImage image) override {
    if (image.block_bytes != sizeof(Block))
      throw std::invalid_argument("triangle blocks of " + std::to_string(image.block_bytes) + " bytes, expected " +
                                  std::to_string(sizeof(Block)) + " for this test and ISA");
    if (reinterpret_cast<std::uintptr_t>(image.nodes) % simd::kAlign != 0 ||
        reinterpret_cast<std::uintptr_t>(image.blocks) % simd::kAlign != 0)
      throw std::invalid_argument("nodes or blocks not 64-byte aligned");
    const auto* nodes = static_cast<const simd::WideNode<simd::kWideN>*>(image.nodes);
    const auto* blocks = static_cast<const Block*>(image.blocks);
    image.stats.depth = check_wide_tree(nodes, image.node_count, image.block_count, image.root);
    nodes_.clear();
    blocks_.clear();
    root_ = image.root;
    stats_ = image.stats;
    set_view(nodes, image.node_count, blocks, image.block_count);
    adopted_ = std::move(image);
  }
  const simd::WideStats& stats() const override { return stats_; }

  void intersect(const RayPacket<16>& rays, HitPacket<16>& hits) const override {
    Kernels::intersect(view_, rays, hits);
  }
  std::uint32_t occluded(const RayPacket<16>& rays) const override { return Kernels::occluded(view_, rays); }
  std::uint32_t occluded(const RayPacket<32>& rays) const override {
    if constexpr (kDouble) {
      return simd::WideKernels<Arch, Test, Robust, 32>::occluded(view_, rays);
    } else {
      // Elsewhere two packets of 16.
      RayPacket<16> half[2];
      for (int h = 0; h < 2; ++h) {
        const float* from[8] = {rays.ox, rays.oy, rays.oz, rays.dx, rays.dy, rays.dz, rays.tmin, rays.tmax};
        float* to[8] = {half[h].ox, half[h].oy, half[h].oz, half[h].dx, half[h].dy, half[h].dz, half[h].tmin, half[h].tmax};
        for (int f = 0; f < 8; ++f) std::memcpy(to[f], from[f] + 16 * h, 16 * sizeof(float));
        half[h].active = (rays.active >> (16 * h)) & 0xffffu;
      }
      return Kernels::occluded(view_, half[0]) | (Kernels::occluded(view_, half[1]) << 16);
    }
  }
  bool double_packets() const override { return kDouble; }
  void occluded(const Ray* rays, std::size_t count, std::uint8_t* blocked) const override {
    Kernels::occluded(view_, rays, count, blocked);
  }
  void intersect(const Ray* rays, std::size_t count, Hit* hits) const override {
    Kernels::intersect(view_, rays, count, hits);
  }
  void occluded(const Ray* rays, std::size_t count, const std::uint32_t* excluded,
                std::uint8_t* blocked) const override {
    Kernels::occluded_excluding(view_, rays, count, excluded, blocked);
  }
  void intersect(const Ray* rays, std::size_t count, const std::uint32_t* excluded, Hit* hits) const override {
    Kernels::intersect_excluding(view_, rays, count, excluded, hits);
  }
  void all_hits(const Ray& ray, std::vector<Hit>& out) const override { Kernels::all_hits(view_, ray, out); }
  WalkCounts walk_counts(const Ray& ray, bool any_hit) const override {
    return Kernels::walk_counts(view_, ray, any_hit);
  }
  void all_hits(const RayPacket<16>& rays, std::vector<Hit>* out) const override { Kernels::all_hits(view_, rays, out); }
  void closest_point(core::PointQuery& query) const override { Kernels::closest_point(view_, query); }

 private:
  /// The kernels' view of `node_count` nodes and `block_count` blocks (root_ set).
  void set_view(const simd::WideNode<simd::kWideN>* nodes, std::size_t node_count, const Block* blocks,
                std::size_t block_count) {
    const std::size_t bytes = node_count * sizeof(simd::WideNode<simd::kWideN>) + block_count * sizeof(Block);
    view_ = {nodes, blocks, root_, bytes >= simd::kDeferHandoffBytes};
  }

  typename Kernels::View view_{nullptr, nullptr, simd::wide_ref::kEmptyRef};
  simd::AlignedVector<simd::WideNode<simd::kWideN>> nodes_;
  simd::AlignedVector<Block> blocks_;
  std::uint32_t root_ = simd::wide_ref::kEmptyRef;
  simd::WideStats stats_;
  WideImage adopted_;  ///< a loaded structure that view_ reads in place (owner set), else empty
};

template <class Arch, bool Robust>
std::unique_ptr<WideAccel> make_for(TriangleTest test) {
  switch (test) {
    case TriangleTest::plane:
      return std::make_unique<WideAccelFor<Arch, TriangleTest::plane, Robust>>();
    case TriangleTest::moller:
      return std::make_unique<WideAccelFor<Arch, TriangleTest::moller, Robust>>();
    case TriangleTest::watertight:
      return std::make_unique<WideAccelFor<Arch, TriangleTest::watertight, Robust>>();
  }
  throw std::invalid_argument("WideAccel::create: unknown triangle test");
}

template <class Arch>
std::unique_ptr<WideAccel> make_for(TriangleTest test, bool robust) {
  return robust ? make_for<Arch, true>(test) : make_for<Arch, false>(test);
}

}  // namespace

std::unique_ptr<WideAccel> WideAccel::create(TriangleTest test, Isa isa, bool robust) {
  if (isa == Isa::automatic || isa == Isa::scalar)
    throw std::invalid_argument("WideAccel::create: resolve the ISA first (scalar runs the oracle)");
  if (!simd::cpu_has(isa))
    throw std::invalid_argument("WideAccel::create: this CPU does not support " + std::string(to_string(isa)));
  return simd::visit_arch(isa, [&]<class Arch>(Arch) { return make_for<Arch>(test, robust); });
}

}  // namespace volley::accel
