// Included by the project's own programs (the test executables, the volley CLI) and only
// active in the ThreadSanitizer build (VOLLEY_SANITIZE=thread): there oneTBB runs on the
// calling threads alone. oneTBB's scheduler is not instrumented, so TSan cannot see how a
// parallel_for hands its caller's data to the workers and reports every hand-over as a
// race (156 such reports in one run of the threads tests, none in volley's code). With
// one oneTBB thread the threads TSan checks are those the programs start themselves: what
// an embedder's threads do with volley.
#pragma once

#if defined(VOLLEY_SANITIZE_THREAD)
#include <oneapi/tbb/global_control.h>

namespace volley::core {
/// Alive from static initialisation to exit; the most restrictive global_control wins,
/// so a test's own wider limit does not lift it.
inline const tbb::global_control tsan_one_thread(tbb::global_control::max_allowed_parallelism, 1);
}  // namespace volley::core
#endif
