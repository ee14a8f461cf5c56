// core::allocate_large / LargeArray: the huge-page mapping path (from its threshold on) and
// the operator new path below it give aligned, writable storage, freed with the same size;
// the arrays the walks read (wide nodes, triangle blocks) take the lower threshold.
#include <doctest/doctest.h>

#include <cstdint>
#include <initializer_list>
#include <new>

#include "core/large_alloc.h"
#include "simd/aligned.h"
#include "simd/triangle/triangle_blocks.h"
#include "simd/wide/wide_bvh.h"

using namespace volley::core;

TEST_CASE("allocate_large: small and large sizes are aligned, writable and freed") {
  for (const std::size_t bytes : {std::size_t{1}, std::size_t{4096}, kLargeAllocBytes - 1, kLargeAllocBytes,
                                  kLargeAllocBytes + 12345, std::size_t{37} << 20}) {
    CAPTURE(bytes);
    auto* p = static_cast<unsigned char*>(allocate_large(bytes, 64));
    REQUIRE(p != nullptr);
    CHECK(reinterpret_cast<std::uintptr_t>(p) % 64 == 0);
    // Every byte writable: the first, the last and one per 4 KiB page.
    for (std::size_t i = 0; i < bytes; i += 4096) p[i] = static_cast<unsigned char>(i >> 12);
    p[bytes - 1] = 0xab;
    CHECK(p[bytes - 1] == 0xab);
    if (bytes >= kLargeAllocBytes) CHECK(reinterpret_cast<std::uintptr_t>(p) % (std::size_t{2} << 20) == 0);
    free_large(p, bytes, 64);
  }
  free_large(nullptr, kLargeAllocBytes, 64);  // a no-op, as delete of nullptr
}

TEST_CASE("allocate_large: absurd sizes throw std::bad_alloc instead of wrapping") {
  CHECK_THROWS_AS(allocate_large(SIZE_MAX, 64), std::bad_alloc);
  CHECK_THROWS_AS(allocate_large(SIZE_MAX - 4096, 64), std::bad_alloc);
  CHECK_THROWS_AS(LargeArray<double>(SIZE_MAX / 4), std::bad_alloc);
}

TEST_CASE("LargeArray: holds n elements, indexable end to end") {
  LargeArray<std::uint32_t> a((kLargeAllocBytes / 4) + 1000);
  for (std::size_t i = 0; i < a.size(); ++i) a[i] = static_cast<std::uint32_t>(i * 3);
  std::uint64_t sum = 0;
  for (std::size_t i = 0; i < a.size(); ++i) sum += a[i];
  const std::uint64_t n = a.size();
  CHECK(sum == 3 * n * (n - 1) / 2);
  LargeArray<double> small(3);
  small[2] = 1.5;
  CHECK(small.get()[2] == 1.5);
}

TEST_CASE("allocate_large: the walked arrays' threshold maps from 1 MiB, and AlignedAllocator picks it by type") {
  static_assert(kWalkedAllocBytes < kLargeAllocBytes);
  static_assert(volley::simd::AlignedAllocator<volley::simd::WideNode<8>>::kHugeFrom == kWalkedAllocBytes);
  static_assert(volley::simd::AlignedAllocator<volley::simd::WatertightBlock<8>>::kHugeFrom == kWalkedAllocBytes);
  static_assert(volley::simd::AlignedAllocator<volley::simd::MollerBlock<16>>::kHugeFrom == kWalkedAllocBytes);
  static_assert(volley::simd::AlignedAllocator<volley::simd::PlaneBlock<4>>::kHugeFrom == kWalkedAllocBytes);
  static_assert(volley::simd::AlignedAllocator<float>::kHugeFrom == kLargeAllocBytes);
  for (const std::size_t bytes : {kWalkedAllocBytes - 64, kWalkedAllocBytes, kWalkedAllocBytes + 4096}) {
    CAPTURE(bytes);
    auto* p = static_cast<unsigned char*>(allocate_large(bytes, 64, kWalkedAllocBytes));
    REQUIRE(p != nullptr);
    p[0] = 1, p[bytes - 1] = 2;
    CHECK(reinterpret_cast<std::uintptr_t>(p) % 64 == 0);
    if (bytes >= kWalkedAllocBytes) CHECK(reinterpret_cast<std::uintptr_t>(p) % (std::size_t{2} << 20) == 0);
    free_large(p, bytes, 64, kWalkedAllocBytes);
  }
  volley::simd::AlignedVector<volley::simd::WideNode<8>> nodes(kWalkedAllocBytes / sizeof(volley::simd::WideNode<8>));
  CHECK(reinterpret_cast<std::uintptr_t>(nodes.data()) % (std::size_t{2} << 20) == 0);
}
