// Run-time ISA choice (see dispatch.cpp).
#pragma once
#include <stdexcept>

#include "volley/options.h"

namespace volley::simd {

/// True when this CPU (and OS) can run kernels built for `isa`.
bool cpu_has(Isa isa);
/// The widest ISA this machine supports.
Isa best_isa();
/// Turns a requested ISA into the one to run: `automatic` honours VOLLEY_ISA, then picks
/// the best. Throws std::invalid_argument for an unsupported request or a bad VOLLEY_ISA.
Isa resolve_isa(Isa requested);

}  // namespace volley::simd
