// WideAccel: the type-erased facade (baseline code). Each implementation forwards to the
// traversal kernels instantiated in the per-ISA files (extern templates in
// simd/wide_traverse.h), so nothing here is compiled with wider instructions.
#include "accel/wide_accel.h"

#include <stdexcept>
#include <string>

#include "accel/wide_build.h"
#include "simd/aligned.h"
#include "simd/dispatch.h"
#include "simd/wide_traverse.h"

namespace volley::accel {
namespace {

template <class Arch, TriangleTest Test, bool Robust>
class WideAccelFor final : public WideAccel {
 public:
  using Kernels = simd::WideKernels<Arch, Test, Robust>;
  using Block = typename Kernels::Block;
  static constexpr int W = Kernels::W;

  WideAccelFor() : WideAccel({&Kernels::intersect_erased, &Kernels::occluded_erased, &view_}) {}
  WideAccelFor(const WideAccelFor&) = delete;  // single_ points at view_
  WideAccelFor& operator=(const WideAccelFor&) = delete;

  int block_width() const override { return W; }

  void build(const core::Bvh& bvh, const float* xyz, const std::uint32_t* ids) override {
    stats_ = build_wide<Test, W>(bvh, xyz, ids, nodes_, blocks_, root_);
    view_ = {nodes_.data(), blocks_.data(), root_};
  }
  void refit(const float* xyz, const std::uint32_t* index_of) override {
    stats_ = refit_wide<Test, W>(xyz, index_of, nodes_, blocks_, stats_);
  }
  const simd::WideStats& stats() const override { return stats_; }

  void intersect(const RayPacket<16>& rays, HitPacket<16>& hits) const override {
    Kernels::intersect(view_, rays, hits);
  }
  std::uint32_t occluded(const RayPacket<16>& rays) const override { return Kernels::occluded(view_, rays); }

 private:
  typename Kernels::View view_{nullptr, nullptr, simd::wide_ref::kEmptyRef};
  simd::AlignedVector<simd::WideNode<simd::kWideN>> nodes_;
  simd::AlignedVector<Block> blocks_;
  std::uint32_t root_ = simd::wide_ref::kEmptyRef;
  simd::WideStats stats_;
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
