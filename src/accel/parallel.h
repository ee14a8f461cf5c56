// Splitting a batch over threads: the caller's oneTBB arena, the calling thread alone, or
// an arena of the thread count asked for (the `threads` argument of Accel's batch forms).
#pragma once
#include <cstddef>
#include <string>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "volley/accel.h"

namespace volley::accel {

/// `p` (the address of a thread's buffer, a thread_local), once. In a shared library (the
/// Python module, libvolley.so) finding a thread_local is a call to __tls_get_addr, and GCC
/// repeats that call at every use (for every ray of a loop) rather than keep the address in
/// a register, unless it cannot tell where the pointer came from.
template <class T>
T* thread_buffer(T* p) {
  asm("" : "+r"(p));
  return p;
}

/// An arena of `threads` slots for the calling thread, made at its first use and kept until
/// the thread ends: a batch call that made its own arena woke and joined its workers anew
/// each time (perf/reports/rays.md, "16 threads"). Per calling thread, so that two callers asking
/// for n threads each still get n each, as with an arena per call.
tbb::task_arena& arena_of(int threads);

/// Whether the batch forms split their work over oneTBB's threads. Not in the
/// ThreadSanitizer build (VOLLEY_SANITIZE_THREAD): oneTBB and its allocator are not
/// instrumented there, so TSan cannot see that memory one thread's tasks freed and another
/// thread's tasks reuse was handed over, and reports the reuse as a race (seen in the test
/// of 8 threads querying one scene). There the chunks run on the calling thread, in order,
/// and TSan checks what the embedder's own threads do with volley.
#if defined(VOLLEY_SANITIZE_THREAD)
inline constexpr bool kChunksOnTbb = false;
#else
inline constexpr bool kChunksOnTbb = true;
#endif

/// Calls body(begin, end) over [0, count) in chunks of at least `grain`: on the current
/// arena (threads = 0), on the calling thread alone (1), or on an arena of `threads`.
/// Throws Error naming `caller` for threads < 0.
template <class Body>
void for_chunks(const char* caller, std::size_t count, int threads, Body&& body, std::size_t grain = 256) {
  if (threads < 0) throw Error(std::string(caller) + ": threads must be >= 0 (0: the caller's oneTBB arena)");
  if (count == 0) return;
  if (threads == 1) {
    body(std::size_t{0}, count);
    return;
  }
  if constexpr (!kChunksOnTbb) {
    for (std::size_t begin = 0; begin < count; begin += grain) body(begin, begin + grain < count ? begin + grain : count);
    return;
  }
  auto run = [&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, grain),
                      [&](const tbb::blocked_range<std::size_t>& r) { body(r.begin(), r.end()); });
  };
  if (threads == 0) {
    run();
  } else {
    arena_of(threads).execute(run);
  }
}

}  // namespace volley::accel
