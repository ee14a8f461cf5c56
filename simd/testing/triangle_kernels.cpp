// TriangleKernels: the type-erased facade (baseline code). Each implementation forwards to
// the kernels instantiated in the per-ISA files (block_kernels.h, extern templates).
#include "simd/testing/triangle_kernels.h"

#include <stdexcept>
#include <string>

#include "simd/aligned.h"
#include "simd/triangle/block_build.h"
#include "simd/triangle/block_kernels.h"
#include "simd/isa/dispatch.h"

namespace volley::simd {
namespace {

template <class Arch, TriangleTest Test>
class KernelsFor final : public TriangleKernels {
 public:
  static constexpr int W = kLanes<Arch>;
  using Block = BlockFor<Test, W>;
  using Single = RayBlockKernels<Arch, Test>;
  using Packets = PacketKernels<Arch, Test, kPacketSize>;

  KernelsFor() : TriangleKernels(Test, kIsaOf<Arch>) {}
  using TriangleKernels::intersect;
  using TriangleKernels::occluded;

  int width() const override { return W; }
  std::size_t bytes() const override { return blocks_.size() * sizeof(Block); }
  std::size_t blocks() const override { return blocks_.size(); }

  std::vector<BlockRange> build(const float* xyz, const std::uint32_t* prim_ids, std::size_t n,
                                const std::uint32_t* groups, std::size_t ngroups) override {
    std::vector<BlockRange> ranges(ngroups);
    std::size_t total = 0;
    for (std::size_t g = 0; g < ngroups; ++g) {
      if (groups[g + 1] < groups[g] || groups[g + 1] > n)
        throw std::invalid_argument("TriangleKernels::build: group " + std::to_string(g) + " is not within 0 .. n");
      total += blocks_for<W>(groups[g + 1] - groups[g]);
    }
    if (total > 0xffffffffu) throw std::length_error("TriangleKernels::build: more than 2^32 - 1 blocks");
    blocks_.assign(total, Block{});
    std::size_t next = 0;
    for (std::size_t g = 0; g < ngroups; ++g) {
      const std::size_t first = groups[g], count = groups[g + 1] - groups[g];
      pack_blocks<Test, W>(xyz + 9 * first, prim_ids + first, count, blocks_.data() + next);
      ranges[g] = {static_cast<std::uint32_t>(next), static_cast<std::uint32_t>(blocks_for<W>(count))};
      next += ranges[g].count;
    }
    return ranges;
  }

  void intersect(const PreparedRay& ray, BlockRange r, Hit& hit) const override {
    Single::intersect(ray, blocks_.data() + r.first, r.count, hit);
  }
  bool occluded(const PreparedRay& ray, BlockRange r) const override {
    return Single::occluded(ray, blocks_.data() + r.first, r.count);
  }
  void prepare(const Packet& rays, PreparedPacket16& out) const override { Packets::prepare(rays, out); }
  void intersect(const PreparedPacket16& rays, BlockRange r, PacketHits& hits) const override {
    Packets::intersect(rays, blocks_.data() + r.first, r.count, hits);
  }
  std::uint32_t occluded(const PreparedPacket16& rays, BlockRange r, std::uint32_t active) const override {
    return Packets::occluded(rays, blocks_.data() + r.first, r.count, active);
  }

 private:
  AlignedVector<Block> blocks_;
};

template <class Arch>
std::unique_ptr<TriangleKernels> make_for(TriangleTest test) {
  switch (test) {
    case TriangleTest::plane:
      return std::make_unique<KernelsFor<Arch, TriangleTest::plane>>();
    case TriangleTest::moller:
      return std::make_unique<KernelsFor<Arch, TriangleTest::moller>>();
    case TriangleTest::watertight:
      return std::make_unique<KernelsFor<Arch, TriangleTest::watertight>>();
  }
  throw std::invalid_argument("TriangleKernels::create: unknown triangle test");
}

}  // namespace

std::unique_ptr<TriangleKernels> TriangleKernels::create(TriangleTest test, Isa isa) {
  if (isa == Isa::automatic || isa == Isa::scalar)
    throw std::invalid_argument("TriangleKernels::create: resolve the ISA first (scalar runs the oracle)");
  if (!cpu_has(isa))
    throw std::invalid_argument("TriangleKernels::create: this CPU does not support " + std::string(to_string(isa)));
  return visit_arch(isa, [&]<class Arch>(Arch) { return make_for<Arch>(test); });
}

}  // namespace volley::simd
