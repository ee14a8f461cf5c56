// Run-time ISA choice: the best instruction set this CPU and OS support, unless forced
// by VOLLEY_ISA. Uses __builtin_cpu_supports, which (unlike xsimd 8.1's detection) checks
// that the OS enabled the wider register state.
#include "simd/isa/dispatch.h"

#include <cstdlib>
#include <string>

namespace volley::simd {

bool cpu_has(Isa isa) {
  __builtin_cpu_init();
  switch (isa) {
    case Isa::scalar:
      return true;
    case Isa::sse42:
      return __builtin_cpu_supports("sse4.2");
    case Isa::avx2:
      return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
    case Isa::avx512:
      return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
             __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512vl");
    case Isa::automatic:
      return true;
  }
  return false;
}

Isa best_isa() {
  for (Isa isa : {Isa::avx512, Isa::avx2, Isa::sse42})
    if (cpu_has(isa)) return isa;
  return Isa::scalar;
}

Isa resolve_isa(Isa requested) {
  if (requested == Isa::automatic) {
    if (const char* env = std::getenv("VOLLEY_ISA")) {
      auto parsed = parse_isa(env);
      if (!parsed) throw std::invalid_argument(std::string("VOLLEY_ISA=") + env + ": expected auto, scalar, sse4.2, avx2 or avx512");
      requested = *parsed;
    }
  }
  if (requested == Isa::automatic) return best_isa();
  if (!cpu_has(requested))
    throw std::invalid_argument(std::string("this CPU does not support ") + std::string(to_string(requested)));
  return requested;
}

StreamTraits stream_traits(Isa isa) {
  const bool wide = isa == Isa::avx512 || isa == Isa::avx2;
  return {wide, wide};
}

}  // namespace volley::simd
