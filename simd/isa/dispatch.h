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

/// What the stream policy may do on an ISA, as measured there (perf/reports/rays.md):
/// `unordered_packets`, runs whose walk needs no order (occlusion, every hit) go as packets
/// though their directions straddle an axis plane (shadow rays); `probe_batches`, a batch
/// call probes whether its rays share their nodes, and if so sends every run as a packet
/// (accel/stream_plan.h).
struct StreamTraits {
  bool unordered_packets = false;
  bool probe_batches = false;
};
StreamTraits stream_traits(Isa isa);

}  // namespace volley::simd
