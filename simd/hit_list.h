// Appending to a list of hits from the per-ISA kernels (the crossing queries' sinks). Out of
// line and compiled for the baseline ISA (hit_list.cpp): a std::vector member instantiated
// in a per-ISA file would be a weak symbol the linker may share with baseline code
// (docs/style.md rule 2; simd/isa/check_weak_symbols.sh catches it where the compiler does not
// inline it).
#pragma once
#include <vector>

#include "volley/ray.h"

namespace volley::simd {

/// out.push_back(h).
void append_hit(std::vector<Hit>& out, const Hit& h);

}  // namespace volley::simd
