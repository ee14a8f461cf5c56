#include "core/large_alloc.h"

#include <cstdint>
#include <new>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace volley::core {

namespace {
constexpr std::size_t kHugePage = std::size_t{2} << 20;

std::size_t round_up(std::size_t bytes) { return (bytes + kHugePage - 1) & ~(kHugePage - 1); }
}  // namespace

void* allocate_large(std::size_t bytes, std::size_t align, std::size_t huge_from) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  if (bytes >= huge_from) {
    if (bytes > SIZE_MAX - 2 * kHugePage) throw std::bad_alloc();  // round_up would wrap
    const std::size_t size = round_up(bytes);
    // Map one huge page more than needed and unmap the misaligned head and the tail.
    void* raw = mmap(nullptr, size + kHugePage, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (raw == MAP_FAILED) throw std::bad_alloc();
    const auto start = reinterpret_cast<std::uintptr_t>(raw);
    const std::uintptr_t aligned = (start + kHugePage - 1) & ~std::uintptr_t{kHugePage - 1};
    if (aligned > start) munmap(raw, aligned - start);
    if (const std::size_t tail = start + size + kHugePage - (aligned + size)) munmap(reinterpret_cast<void*>(aligned + size), tail);
    void* p = reinterpret_cast<void*>(aligned);
    madvise(p, size, MADV_HUGEPAGE);  // advice only: 4 KiB pages where refused
    return p;
  }
#endif
  return ::operator new(bytes, std::align_val_t(align));
}

void free_large(void* p, std::size_t bytes, std::size_t align, std::size_t huge_from) noexcept {
  if (p == nullptr) return;
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  if (bytes >= huge_from) {
    munmap(p, round_up(bytes));
    return;
  }
#endif
  ::operator delete(p, std::align_val_t(align));
}

}  // namespace volley::core
